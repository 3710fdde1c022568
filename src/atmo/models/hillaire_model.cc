#include "models/hillaire_model.h"

#include <algorithm>
#include <chrono>
#include <mutex>
#include <cmath>
#include <string>

#include <oneapi/tbb/parallel_for.h>

#include "atmo/error.h"
#include "cpu/hillaire_tables.h"
#include "cpu/sky_view_lookup.h"
#include "models/model_options.h"
#include "physics/shared_parameters.h"

namespace atmo {
namespace {

using Clock = std::chrono::steady_clock;

}  // namespace

HillaireSettings HillaireSettings::FromOptions(const ModelOptions& options) {
  HillaireSettings s;
  bool gather_directions_given = false;
  for (const auto& [key, value] : options) {
    if (key == "transmittance_lut") s.transmittance_lut = ParseSizeOption(key, value, 2, 4096);
    else if (key == "transmittance_samples") s.transmittance_samples = ParseIntOption(key, value, 1, 100000);
    else if (key == "multiple_scattering_lut") s.multiple_scattering_lut = ParseSizeOption(key, value, 2, 4096);
    else if (key == "multiple_scattering_directions") {
      s.multiple_scattering_directions = ParseIntOption(key, value, 2, 65536);
      if (s.multiple_scattering_directions % 2 != 0) {
        throw Error("option multiple_scattering_directions=" + value +
                    ": expected an even number (a lattice and its mirror image; 2 = up and down)");
      }
    }
    else if (key == "multiple_scattering_samples") s.multiple_scattering_samples = ParseIntOption(key, value, 1, 100000);
    else if (key == "multiple_scattering_orders") s.multiple_scattering_orders = ParseIntOption(key, value, 1, 32);
    else if (key == "multiple_scattering_gather_directions") {
      s.multiple_scattering_gather_directions = ParseIntOption(key, value, 2, 65536);
      gather_directions_given = true;
      if (s.multiple_scattering_gather_directions % 2 != 0) {
        throw Error("option multiple_scattering_gather_directions=" + value +
                    ": expected an even number (a lattice and its mirror image; 2 = up and down)");
      }
    }
    else if (key == "sky_view_lut") {
      s.sky_view_lut = ParseSizeOption(key, value, 2, 8192);
      if (s.sky_view_lut.y % 2 != 0 || s.sky_view_lut.y < 4) {
        throw Error("option sky_view_lut=" + value + ": the height must be even and >= 4 (sky and ground halves)");
      }
    }
    else if (key == "sky_view_samples") s.sky_view_samples = ParseIntOption(key, value, 1, 100000);
    else if (key == "ray_march_samples") s.ray_march_samples = ParseIntOption(key, value, 1, 100000);
    else if (key == "ground_irradiance_lut") s.ground_irradiance_lut = ParseIntOption(key, value, 2, 4096);
    else if (key == "ground_irradiance_directions") s.ground_irradiance_directions = ParseIntOption(key, value, 1, 65536);
    else if (key == "ground_irradiance_samples") s.ground_irradiance_samples = ParseIntOption(key, value, 1, 100000);
    else if (key == "multiple_scattering_phase") {
      if (value != "media" && value != "isotropic") {
        throw Error("option multiple_scattering_phase=" + value + ": expected media or isotropic");
      }
      s.multiple_scattering_media_phase = value == "media";
    } else if (key == "multiple_scattering_ground") {
      if (value != "on" && value != "off") throw Error("option multiple_scattering_ground=" + value + ": expected on or off");
      s.multiple_scattering_ground = value == "on";
    } else if (key == "sky_view") {
      if (value != "auto" && value != "off") throw Error("option sky_view=" + value + ": expected auto or off");
      s.use_sky_view_lut = value == "auto";
    } else {
      throw Error("unknown option '" + key + "' for model hillaire (known: transmittance_lut, transmittance_samples, "
                  "multiple_scattering_lut, multiple_scattering_directions, multiple_scattering_samples, "
                  "multiple_scattering_phase, multiple_scattering_ground, multiple_scattering_orders, "
                  "multiple_scattering_gather_directions, "
                  "sky_view_lut, sky_view_samples, ray_march_samples, sky_view, ground_irradiance_lut, "
                  "ground_irradiance_directions, ground_irradiance_samples)");
    }
  }
  // The gathered orders use order 1's directions unless told otherwise (the seed's pair stays a pair).
  if (!gather_directions_given) s.multiple_scattering_gather_directions = s.multiple_scattering_directions;
  return s;
}

HillaireModel::HillaireModel(const AtmosphereParameters& parameters, const HillaireSettings& settings)
    : Model(parameters), settings_(settings) {
  Validate(parameters);
  if (parameters.geometry != Geometry::kSpherical) {
    throw Error("model hillaire needs a spherical atmosphere; the half-space of preset '" + parameters.name +
                "' is the geometry of the simple model");
  }
  for (std::size_t b = 0; b < ChannelBatchCount(parameters.channel_count()); ++b) {
    Batch batch;
    batch.atmosphere = ToSharedParameters(parameters, b);
    batches_.push_back(std::move(batch));
  }
}

void HillaireModel::ComputeMultipleScatteringLut(Batch& batch) const {
  const glm::ivec2 size = settings_.multiple_scattering_lut;
  batch.multiple_scattering = shared::Texture2D(size.x, size.y);
  const shared::vec3 ground_transfer =
      settings_.multiple_scattering_ground
          ? shared::GetGroundTransfer(batch.atmosphere, settings_.multiple_scattering_directions / 2,
                                      settings_.multiple_scattering_samples)
          : shared::vec3(0.0);
  cpu::ComputeMultipleScatteringTable(batch.atmosphere, batch.transmittance, settings_.multiple_scattering_directions,
                                      settings_.multiple_scattering_samples, settings_.multiple_scattering_media_phase,
                                      ground_transfer, batch.multiple_scattering, settings_.multiple_scattering_orders,
                                      settings_.multiple_scattering_gather_directions);
}

void HillaireModel::Precompute() {
  auto start = Clock::now();
  // All batches in one pass: the density integrals are shared (cpu::ComputeTransmittanceTables).
  {
    const glm::ivec2 size = settings_.transmittance_lut;
    std::vector<shared::AtmosphereParameters> atmospheres;
    std::vector<shared::Texture2D*> tables;
    for (Batch& batch : batches_) {
      batch.transmittance = shared::Texture2D(size.x, size.y);
      atmospheres.push_back(batch.atmosphere);
      tables.push_back(&batch.transmittance);
    }
    cpu::ComputeTransmittanceTables(atmospheres, settings_.transmittance_samples, tables);
  }
  RecordPass("transmittance_lut", MillisecondsSince(start));
  start = Clock::now();
  for (Batch& batch : batches_) ComputeMultipleScatteringLut(batch);
  RecordPass("multiple_scattering_lut", MillisecondsSince(start));
  start = Clock::now();
  for (Batch& batch : batches_) ComputeGroundIrradianceLut(batch);
  RecordPass("ground_irradiance_lut", MillisecondsSince(start));
}

void HillaireModel::ComputeGroundIrradianceLut(Batch& batch) const {
  const int width = settings_.ground_irradiance_lut;
  batch.ground_irradiance = shared::Texture2D(width, 1);
  cpu::ComputeGroundIrradianceTable(batch.atmosphere, batch.transmittance, batch.multiple_scattering,
                                    settings_.ground_irradiance_directions, settings_.ground_irradiance_samples,
                                    batch.ground_irradiance);
}

void HillaireModel::AddGroundView(const Batch& batch, double r, double mu_s, shared::Texture2D& table) const {
  const shared::ivec2 size(table.width, table.height);
  oneapi::tbb::parallel_for(0, size.y, [&](int y) {
    for (int x = 0; x < size.x; ++x) {
      table.at(x, y) += glm::vec3(shared::ComputeGroundViewTexel(batch.atmosphere, batch.transmittance,
                                                                 batch.ground_irradiance, size,
                                                                 shared::vec2(x + 0.5, y + 0.5), r, mu_s));
    }
  });
}

shared::Texture2D HillaireModel::ComputeSkyViewLut(const Batch& batch, double r, double mu_s) const {
  const glm::ivec2 size = settings_.sky_view_lut;
  shared::Texture2D sky_view(size.x, size.y, /*repeat=*/true);
  cpu::ComputeSkyViewTable(batch.atmosphere, batch.transmittance, batch.multiple_scattering, r, mu_s,
                           settings_.sky_view_samples, sky_view);
  return sky_view;
}

// The per-view state: the observer's radius and the sun, and the sky-view tables when they serve.
class HillaireSkyView final : public SkyView {
 public:
  HillaireSkyView(const HillaireModel& model, double altitude_m, const glm::dvec3& sun)
      : SkyView(altitude_m, sun, model.channel_count(), model.parameters().sun_angular_radius_rad),
        model_(model),
        r_(model.parameters().ground_radius_m + altitude_m),
        mu_s_(shared::ClampCosine(sun.z)) {
    const auto& batches = model.batches();
    horizon_nadir_angle_ = shared::GetHorizonNadirAngle(batches.front().atmosphere, r_);
    if (model.settings().use_sky_view_lut && r_ <= batches.front().atmosphere.top_radius) {
      auto start = Clock::now();
      for (const auto& batch : batches) sky_view_.push_back(model.ComputeSkyViewLut(batch, r_, mu_s_));
      model.RecordPass("sky_view_lut", MillisecondsSince(start));
      // For images: the same table with the ground's reflected light added below the horizon.
      start = Clock::now();
      for (std::size_t b = 0; b < batches.size(); ++b) {
        sky_and_ground_view_.push_back(sky_view_[b]);
        model.AddGroundView(batches[b], r_, mu_s_, sky_and_ground_view_.back());
      }
      model.RecordPass("ground_view_lut", MillisecondsSince(start));
      // Three channels: the frame kernel's float copies of both tables.
      if (batches.size() == 1) {
        sky_lookup_ = cpu::MakeSkyViewLookup(sky_view_[0], horizon_nadir_angle_, sun);
        sky_and_ground_lookup_ = cpu::MakeSkyViewLookup(sky_and_ground_view_[0], horizon_nadir_angle_, sun);
      }
    }
  }

  void Radiance(const glm::dvec3& view, std::span<double> out) const override {
    const double nu = glm::dot(view, sun_direction());
    const double azimuth = shared::GetAzimuthFromSun(view, sun_direction());
    ScatterBatches(model_.batches().size(), out, [&](std::size_t b) {
      const HillaireModel::Batch& batch = model_.batches()[b];
      if (!sky_view_.empty()) {
        return shared::GetSkyRadianceFromSkyView(batch.atmosphere, sky_view_[b], r_, view.z, azimuth);
      }
      shared::vec3 transmittance;
      return shared::IntegrateScatteredRadiance(batch.atmosphere, batch.transmittance, batch.multiple_scattering, r_,
                                                view.z, mu_s_, nu, 1e300, model_.settings().ray_march_samples,
                                                transmittance);
    });
  }

  void Transmittance(const glm::dvec3& view, std::span<double> out) const override {
    ScatterBatches(model_.batches().size(), out, [&](std::size_t b) {
      const HillaireModel::Batch& batch = model_.batches()[b];
      return shared::GetViewTransmittance(batch.atmosphere, batch.transmittance, r_, view.z);
    });
  }

  void SunDiscRadiance(const glm::dvec3& view, std::span<double> out) const override {
    const double nu = glm::dot(view, sun_direction());
    ScatterBatches(model_.batches().size(), out, [&](std::size_t b) {
      const HillaireModel::Batch& batch = model_.batches()[b];
      return shared::GetSunDiscRadiance(batch.atmosphere, batch.transmittance, r_, view.z, nu);
    });
  }

  void GroundRadiance(const glm::dvec3& view, std::span<double> out) const override {
    const double nu = glm::dot(view, sun_direction());
    ScatterBatches(model_.batches().size(), out, [&](std::size_t b) {
      const HillaireModel::Batch& batch = model_.batches()[b];
      return shared::GetGroundRadiance(batch.atmosphere, batch.transmittance, batch.ground_irradiance, r_, view.z, mu_s_,
                                       nu);
    });
  }

  void ScatteringAlongSegment(const glm::dvec3& view, double distance_m, std::span<double> radiance,
                              std::span<double> transmittance) const override {
    const double nu = glm::dot(view, sun_direction());
    const auto& batches = model_.batches();
    for (std::size_t b = 0; b < batches.size(); ++b) {
      shared::vec3 t;
      const shared::vec3 l = shared::IntegrateScatteredRadiance(batches[b].atmosphere, batches[b].transmittance,
                                                                batches[b].multiple_scattering, r_, view.z, mu_s_, nu,
                                                                distance_m, model_.settings().ray_march_samples, t);
      for (std::size_t i = 0; i < 3 && 3 * b + i < radiance.size(); ++i) {
        radiance[3 * b + i] = l[static_cast<int>(i)];
        transmittance[3 * b + i] = t[static_cast<int>(i)];
      }
    }
  }

  void RadianceBatch(std::span<const glm::dvec3> views, const RadianceTerms& terms,
                     std::span<float> out) const override {
    if (sky_view_.empty()) {  // per-pixel ray marching
      SkyView::RadianceBatch(views, terms, out);
      return;
    }
    cpu::LookupSkyViewBatch(*this, terms.ground ? sky_and_ground_lookup_ : sky_lookup_,
                            terms.ground ? sky_and_ground_view_ : sky_view_, horizon_nadir_angle_, terms.sun_disc, views,
                            out);
  }

  // The sky-view tables of every batch folded into one three-channel table per weight set: a
  // spectral frame then costs one lookup per pixel, as a 3-channel one. The folded lookups are
  // made on first use and kept for the last weights asked for.
  void RadianceBatchFolded(std::span<const glm::dvec3> views, const RadianceTerms& terms,
                           std::span<const glm::vec3> weights, std::span<float> out) const override {
    if (sky_view_.empty()) {
      SkyView::RadianceBatchFolded(views, terms, weights, out);
      return;
    }
    const std::size_t n = channel_count();
    if (weights.size() != n) throw Error("RadianceBatchFolded needs one weight per channel");
    const cpu::SkyViewLookup* lookup = nullptr;
    {
      std::lock_guard<std::mutex> lock(folded_mutex_);
      if (!std::equal(weights.begin(), weights.end(), folded_weights_.begin(), folded_weights_.end())) {
        folded_weights_.assign(weights.begin(), weights.end());
        folded_sky_ = cpu::MakeSkyViewLookup(Fold(sky_view_, weights), horizon_nadir_angle_, sun_direction());
        folded_sky_and_ground_ =
            cpu::MakeSkyViewLookup(Fold(sky_and_ground_view_, weights), horizon_nadir_angle_, sun_direction());
      }
      lookup = terms.ground ? &folded_sky_and_ground_ : &folded_sky_;
    }
    cpu::LookupFoldedSkyViewBatch(*this, *lookup, weights, terms.sun_disc, views, out);
  }

 private:
  // sum over channels of weights[c] x table_b(c): the per-batch tables as one folded table.
  static shared::Texture2D Fold(const std::vector<shared::Texture2D>& tables, std::span<const glm::vec3> weights) {
    shared::Texture2D folded(tables.front().width, tables.front().height, tables.front().repeat_u);
    for (std::size_t b = 0; b < tables.size(); ++b) {
      for (std::size_t t = 0; t < folded.texels.size(); ++t) {
        const glm::vec3& l = tables[b].texels[t];
        for (std::size_t c = 0; c < 3 && 3 * b + c < weights.size(); ++c) {
          folded.texels[t] += weights[3 * b + c] * l[static_cast<int>(c)];
        }
      }
    }
    return folded;
  }

  const HillaireModel& model_;
  double r_;
  double mu_s_;
  double horizon_nadir_angle_;                       // GetHorizonNadirAngle(r_), for per-pixel lookups
  std::vector<shared::Texture2D> sky_view_;  // one per batch; empty where the table does not serve
  std::vector<shared::Texture2D> sky_and_ground_view_;  // sky_view_ plus the lit ground, for images
  cpu::SkyViewLookup sky_lookup_;             // float frame-kernel copies (three channels only)
  cpu::SkyViewLookup sky_and_ground_lookup_;
  mutable std::mutex folded_mutex_;  // guards the folded lookups below
  mutable std::vector<glm::vec3> folded_weights_;
  mutable cpu::SkyViewLookup folded_sky_;
  mutable cpu::SkyViewLookup folded_sky_and_ground_;
};

std::unique_ptr<SkyView> HillaireModel::View(double altitude_m, const glm::dvec3& sun_direction) const {
  if (!std::isfinite(altitude_m) || altitude_m < 0.0) {
    throw Error("altitude_m must be finite and >= 0 for model hillaire (got " + std::to_string(altitude_m) + ")");
  }
  CheckDirection(sun_direction, "the sun direction");
  return std::make_unique<HillaireSkyView>(*this, altitude_m, glm::normalize(sun_direction));
}

}  // namespace atmo
