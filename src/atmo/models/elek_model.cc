#include "models/elek_model.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <string>

#include <oneapi/tbb/task_arena.h>

#include "atmo/error.h"
#include "atmo/memory.h"
#include "cpu/hillaire_tables.h"
#include "io/elek_table_file.h"
#include "io/table_cache_file.h"
#include "models/model_options.h"
#include "physics/shared_parameters.h"

namespace atmo {
namespace {

using Clock = std::chrono::steady_clock;

glm::ivec3 ParseSize3(const std::string& key, const std::string& value) {
  const std::size_t a = value.find('x');
  const std::size_t b = a == std::string::npos ? std::string::npos : value.find('x', a + 1);
  if (b == std::string::npos) throw Error("option " + key + "=" + value + ": expected WxHxD, e.g. 32x256x32");
  return {ParseIntOption(key, value.substr(0, a), 2, 1024), ParseIntOption(key, value.substr(a + 1, b - a - 1), 2, 4096),
          ParseIntOption(key, value.substr(b + 1), 2, 1024)};
}

std::string Choice(const std::string& key, const std::string& value, std::initializer_list<const char*> choices) {
  std::string known;
  for (const char* c : choices) {
    if (value == c) return value;
    known += (known.empty() ? "" : " or ") + std::string(c);
  }
  throw Error("option " + key + "=" + value + ": expected " + known);
}

}  // namespace

ElekSettings ElekSettings::FromOptions(const ModelOptions& options) {
  ElekSettings s;
  for (const auto& [key, value] : options) {
    if (key == "size") s.size = ParseSize3(key, value);
    else if (key == "mapping") {
      s.mapping = Choice(key, value, {"nonlinear", "linear"}) == "linear" ? shared::kElekMappingLinear
                                                                          : shared::kElekMappingNonLinear;
    } else if (key == "orders") s.orders = ParseIntOption(key, value, 1, 16);
    else if (key == "samples") s.samples = ParseIntOption(key, value, 1, 100000);
    else if (key == "steps") {
      s.steps = Choice(key, value, {"quadratic", "uniform"}) == "uniform" ? shared::kElekStepsUniform
                                                                          : shared::kElekStepsQuadratic;
    } else if (key == "rayleigh_phase") s.rayleigh_phase = Choice(key, value, {"parameters", "rayleigh", "modified"});
    else if (key == "gather") s.phase_gather = Choice(key, value, {"seed", "phase"}) == "phase";
    else if (key == "coupling") s.coupled = Choice(key, value, {"separate", "total"}) == "total";
    else if (key == "mie") s.mie_per_channel = Choice(key, value, {"alpha", "rgb"}) == "rgb";
    else if (key == "ground") s.ground = Choice(key, value, {"auto", "on", "off"});
    else if (key == "gather_rows") s.gather_rows = ParseIntOption(key, value, 2, 4096);
    else if (key == "gather_points") {
      s.gather_points = ParseIntOption(key, value, 1, 4);
      if (s.gather_points == 3) throw Error("option gather_points=3: expected 1, 2 or 4");
    } else if (key == "gather_azimuths") s.gather_azimuths = ParseIntOption(key, value, 2, 65536);
    else if (key == "transmittance_lut") s.transmittance_lut = ParseSizeOption(key, value, 2, 4096);
    else if (key == "transmittance_samples") s.transmittance_samples = ParseIntOption(key, value, 1, 100000);
    else if (key == "table") {
      if (value.empty()) throw Error("option table= needs a file name (NAME of NAME.json, NAME.raw)");
      s.table = value;
    } else {
      throw Error("unknown option '" + key + "' for model elek (known: size, mapping, orders, samples, steps, "
                  "rayleigh_phase, gather, coupling, mie, ground, gather_rows, gather_points, gather_azimuths, "
                  "transmittance_lut, transmittance_samples, table)");
    }
  }
  if (s.mie_per_channel && !s.table.empty()) {
    throw Error("option mie=rgb needs the per-channel Mie of a computed table; a loaded table has one Mie channel");
  }
  return s;
}

std::vector<std::pair<std::string, std::string>> ElekSettings::TableOptions() const {
  const auto i = [](int v) { return std::to_string(v); };
  return {
      {"size", i(size.x) + "x" + i(size.y) + "x" + i(size.z)},
      {"mapping", mapping == shared::kElekMappingLinear ? "linear" : "nonlinear"},
      {"orders", i(orders)},
      {"samples", i(samples)},
      {"steps", steps == shared::kElekStepsUniform ? "uniform" : "quadratic"},
      {"rayleigh_phase", rayleigh_phase},
      {"gather", phase_gather ? "phase" : "seed"},
      {"coupling", coupled ? "total" : "separate"},
      {"ground", ground},
      {"gather_rows", i(gather_rows)},
      {"gather_points", i(gather_points)},
      {"gather_azimuths", i(gather_azimuths)},
      {"transmittance_lut", i(transmittance_lut.x) + "x" + i(transmittance_lut.y)},
      {"transmittance_samples", i(transmittance_samples)},
  };
}

bool ElekSettings::UsesGround(const AtmosphereParameters& parameters) const {
  if (ground == "off") return false;
  return std::any_of(parameters.ground_albedo.begin(), parameters.ground_albedo.end(), [](double a) { return a > 0.0; });
}

ElekModel::ElekModel(const AtmosphereParameters& parameters, const ElekSettings& settings)
    : Model(parameters), settings_(settings) {
  Validate(parameters);
  if (parameters.geometry != Geometry::kSpherical) {
    throw Error("model elek needs a spherical atmosphere; the half-space of preset '" + parameters.name +
                "' is the geometry of the simple model");
  }
  for (std::size_t b = 0; b < ChannelBatchCount(parameters.channel_count()); ++b) {
    Batch batch;
    batch.atmosphere = ToSharedParameters(parameters, b);
    if (settings.rayleigh_phase == "rayleigh") batch.atmosphere.rayleigh_phase = shared::kPhaseRayleigh;
    if (settings.rayleigh_phase == "modified") batch.atmosphere.rayleigh_phase = shared::kPhaseModifiedRayleigh;
    batches_.push_back(std::move(batch));
  }
  // Measured peak memory (docs/reliability.md, "Memory"): 120-128 bytes per texel and batch of 3
  // channels, over a base of ~9 MB.
  const double texels = static_cast<double>(settings.size.x) * settings.size.y * settings.size.z;
  CheckMemory("elek tables of size=" + std::to_string(settings.size.x) + "x" + std::to_string(settings.size.y) + "x" +
                  std::to_string(settings.size.z) + " at " + std::to_string(parameters.channel_count()) + " channels",
              128.0 * texels * static_cast<double>(batches_.size()) + 16e6);
}

double ElekModel::EstimatedPrecomputeSeconds() const {
  // Measured (`atmo sample --model elek`, docs/reliability.md's memory runs): the default
  // 32x256x32 table with K = 4 at 3 channels in ~1.0 s of precomputation on 2 threads, about
  // 2 us of CPU per texel and order; it grows with the texels, the orders and the batches.
  const double texels = static_cast<double>(settings_.size.x) * settings_.size.y * settings_.size.z;
  const double cpu_seconds = 2e-6 * texels * std::max(settings_.orders, 1) * static_cast<double>(batches_.size());
  return cpu_seconds / std::max(oneapi::tbb::this_task_arena::max_concurrency(), 1);
}

cpu::ElekGrid ElekModel::grid() const {
  cpu::ElekGrid grid;
  grid.size = settings_.size;
  grid.mapping = settings_.mapping;
  grid.steps = settings_.steps;
  grid.sample_count = settings_.samples;
  return grid;
}

// Passes: the transmittance table (sun rays), order 1, then per order k the gather of order k - 1
// (its own 3D table, W x gather_rows x D, see elek.glsl) and the scattering pass that reads it.
void ElekModel::ComputeTables(Batch& batch) const {
  const cpu::ElekGrid g = grid();
  auto start = Clock::now();
  batch.orders.assign(1, cpu::ElekScattering());
  cpu::ComputeElekSingleScatteringTable(batch.atmosphere, batch.transmittance, g, batch.orders[0]);
  RecordPass("elek_single_lut", MillisecondsSince(start));
  std::vector<glm::dvec2> matrix;
  if (settings_.orders >= 2) {
    start = Clock::now();
    matrix = cpu::ComputeElekGatherMatrix(batch.atmosphere, g.mapping, settings_.gather_rows, g.size.y,
                                          settings_.gather_points, settings_.gather_azimuths);
    RecordPass("elek_gather_matrix_lut", MillisecondsSince(start));
  }
  const bool ground = settings_.UsesGround(parameters());
  for (int k = 2; k <= settings_.orders; ++k) {
    start = Clock::now();
    cpu::ElekScattering gather_0, gather_pi;
    const bool phase = settings_.phase_gather && k == 2;
    if (phase) {
      cpu::ComputeElekPhaseGatherTables(batch.atmosphere, g.mapping, settings_.gather_rows, batch.orders[0],
                                        settings_.coupled, settings_.gather_points == 4 ? 2 : settings_.gather_points,
                                        settings_.gather_azimuths, gather_0, gather_pi);
    } else {
      cpu::ComputeElekGatherTable(matrix, settings_.gather_rows, batch.orders[k - 2], settings_.coupled, gather_0);
    }
    RecordPass("elek_gather_" + std::to_string(k) + "_lut", MillisecondsSince(start));
    if (ground) {
      // The ground's light of k - 1 events: the reflection of E^(k-2) (the sun itself for k = 2).
      start = Clock::now();
      const shared::Texture2D irradiance = cpu::ComputeElekGroundIrradiance(
          batch.atmosphere, batch.transmittance, k == 2 ? nullptr : &batch.orders[k - 3], g, settings_.gather_azimuths);
      const shared::Texture3D radiance =
          cpu::ComputeElekGroundRadianceTable(batch.atmosphere, batch.transmittance, irradiance, g);
      cpu::AddElekGatheredGround(matrix, radiance, gather_0);
      if (phase) cpu::AddElekGatheredGround(matrix, radiance, gather_pi);
      RecordPass("elek_ground_" + std::to_string(k) + "_lut", MillisecondsSince(start));
    }
    start = Clock::now();
    cpu::ElekScattering order;
    cpu::ComputeElekMultipleScatteringTable(batch.atmosphere, gather_0, phase ? gather_pi : gather_0, g, order);
    batch.orders.push_back(std::move(order));
    RecordPass("elek_scatter_" + std::to_string(k) + "_lut", MillisecondsSince(start));
  }
  start = Clock::now();
  batch.total = batch.orders[0];
  for (std::size_t k = 1; k < batch.orders.size(); ++k) {
    auto& r = batch.total.rayleigh.texels;
    auto& m = batch.total.mie.texels;
    for (std::size_t i = 0; i < r.size(); ++i) {
      r[i] += batch.orders[k].rayleigh.texels[i];
      m[i] += batch.orders[k].mie.texels[i];
    }
  }
  RecordPass("elek_sum_lut", MillisecondsSince(start));
}

void ElekModel::Precompute() {
  auto start = Clock::now();
  for (Batch& batch : batches_) {
    batch.transmittance = shared::Texture2D(settings_.transmittance_lut.x, settings_.transmittance_lut.y);
    cpu::ComputeTransmittanceTable(batch.atmosphere, settings_.transmittance_samples, batch.transmittance);
  }
  RecordPass("elek_transmittance_lut", MillisecondsSince(start));
  if (!settings_.table.empty()) {
    start = Clock::now();
    LoadElekTable(settings_.table, *this);
    RecordPass("elek_load", MillisecondsSince(start));
    return;
  }
  for (Batch& batch : batches_) ComputeTables(batch);
}

std::vector<float> ElekModel::Rgba(std::size_t b) const {
  const Batch& batch = batches_.at(b);
  const std::size_t n = batch.total.rayleigh.texels.size();
  std::vector<float> rgba(4 * n);
  for (std::size_t i = 0; i < n; ++i) {
    const glm::vec3 r = batch.total.rayleigh.texels[i];
    rgba[4 * i + 0] = r.x;
    rgba[4 * i + 1] = r.y;
    rgba[4 * i + 2] = r.z;
    rgba[4 * i + 3] = batch.total.mie.texels[i].x;  // the Mie of the batch's first channel
  }
  return rgba;
}

void ElekModel::SetRgba(std::size_t b, const std::vector<float>& rgba) {
  Batch& batch = batches_.at(b);
  const glm::ivec3 s = settings_.size;
  batch.orders.clear();
  batch.total = cpu::ElekScattering(s.x, s.y, s.z);
  const std::size_t n = batch.total.rayleigh.texels.size();
  if (rgba.size() != 4 * n) throw Error("elek table: expected " + std::to_string(4 * n) + " floats");
  for (std::size_t i = 0; i < n; ++i) {
    batch.total.rayleigh.texels[i] = glm::vec3(rgba[4 * i], rgba[4 * i + 1], rgba[4 * i + 2]);
    batch.total.mie.texels[i] = glm::vec3(rgba[4 * i + 3]);
  }
}

void ElekModel::SetComputedTables(std::size_t b, shared::Texture2D transmittance,
                                  std::vector<cpu::ElekScattering> orders, cpu::ElekScattering total) {
  if (!settings_.table.empty()) {
    throw Error("model elek loads its table (option table=" + settings_.table + "); it takes no computed tables");
  }
  Batch& batch = batches_.at(b);
  const glm::ivec3 s = settings_.size;
  const auto same_size = [&](const cpu::ElekScattering& t) {
    const auto sized = [&](const shared::Texture3D& c) { return c.width == s.x && c.height == s.y && c.depth == s.z; };
    return sized(t.rayleigh) && sized(t.mie);
  };
  bool ok = transmittance.width == settings_.transmittance_lut.x &&
            transmittance.height == settings_.transmittance_lut.y &&
            orders.size() == static_cast<std::size_t>(settings_.orders) && same_size(total);
  for (const cpu::ElekScattering& order : orders) ok = ok && same_size(order);
  if (!ok) throw Error("elek tables: the computed tables do not have the sizes and order count of the settings");
  batch.transmittance = std::move(transmittance);
  batch.orders = std::move(orders);
  batch.total = std::move(total);
}

bool ElekModel::SaveTables(std::vector<unsigned char>& bytes) const {
  if (!settings_.table.empty()) return false;  // the file is the table; it may change on disk
  io::TableBytesWriter out;
  out.Int(static_cast<std::int64_t>(batches_.size()));
  for (const Batch& batch : batches_) {
    out.Texture(batch.transmittance);
    out.Texture(batch.total.rayleigh);
    out.Texture(batch.total.mie);
  }
  bytes = std::move(out.bytes());
  return true;
}

bool ElekModel::LoadTables(std::span<const unsigned char> bytes) {
  if (!settings_.table.empty()) return false;
  io::TableBytesReader in(bytes);
  std::int64_t count = 0;
  if (!in.Int(count) || count != static_cast<std::int64_t>(batches_.size())) return false;
  const glm::ivec3 s = settings_.size;
  const auto sized = [&](const shared::Texture3D& t) { return t.width == s.x && t.height == s.y && t.depth == s.z; };
  std::vector<shared::Texture2D> transmittance(batches_.size());
  std::vector<cpu::ElekScattering> total(batches_.size());
  for (std::size_t b = 0; b < batches_.size(); ++b) {
    if (!in.Texture(transmittance[b]) || !in.Texture(total[b].rayleigh) || !in.Texture(total[b].mie) ||
        transmittance[b].width != settings_.transmittance_lut.x ||
        transmittance[b].height != settings_.transmittance_lut.y || !sized(total[b].rayleigh) ||
        !sized(total[b].mie)) {
      return false;
    }
  }
  if (!in.Finished()) return false;
  for (std::size_t b = 0; b < batches_.size(); ++b) {
    batches_[b].transmittance = std::move(transmittance[b]);
    batches_[b].orders.clear();
    batches_[b].total = std::move(total[b]);
  }
  return true;
}

shared::vec3 ElekModel::BatchRadiance(const Batch& batch, double r, double mu, double mu_s, double nu) const {
  return shared::GetElekRadiance(batch.atmosphere, batch.total.rayleigh, batch.total.mie, settings_.mapping,
                                 settings_.mie_per_channel, r, mu, mu_s, nu);
}

// The per-view state: the observer radius and the sun. The table has no per-view part.
class ElekSkyView final : public SkyView {
 public:
  ElekSkyView(const ElekModel& model, double altitude_m, const glm::dvec3& sun)
      : SkyView(altitude_m, sun, model.channel_count(), model.parameters().sun_angular_radius_rad),
        model_(model),
        r_(model.parameters().ground_radius_m + altitude_m),
        mu_s_(shared::ClampCosine(sun.z)) {}

  void Radiance(const glm::dvec3& view, std::span<double> out) const override {
    const double nu = shared::ClampCosine(glm::dot(view, sun_direction()));
    ScatterBatches(model_.batches().size(), out, [&](std::size_t b) {
      const ElekModel::Batch& batch = model_.batches()[b];
      return model_.BatchRadiance(batch, r_, shared::ClampCosine(view.z), mu_s_, nu);
    });
  }

  void Transmittance(const glm::dvec3& view, std::span<double> out) const override {
    ScatterBatches(model_.batches().size(), out, [&](std::size_t b) {
      const ElekModel::Batch& batch = model_.batches()[b];
      return shared::GetViewTransmittance(batch.atmosphere, batch.transmittance, r_, shared::ClampCosine(view.z));
    });
  }

  void SunDiscRadiance(const glm::dvec3& view, std::span<double> out) const override {
    const double nu = glm::dot(view, sun_direction());
    ScatterBatches(model_.batches().size(), out, [&](std::size_t b) {
      const ElekModel::Batch& batch = model_.batches()[b];
      return shared::GetSunDiscRadiance(batch.atmosphere, batch.transmittance, r_, shared::ClampCosine(view.z), nu);
    });
  }

 private:

  const ElekModel& model_;
  double r_;
  double mu_s_;
};

std::unique_ptr<SkyView> ElekModel::View(double altitude_m, const glm::dvec3& sun_direction) const {
  if (!std::isfinite(altitude_m) || altitude_m < 0.0) {
    throw Error("altitude_m must be finite and >= 0 for model elek (got " + std::to_string(altitude_m) + ")");
  }
  CheckDirection(sun_direction, "the sun direction");
  return std::make_unique<ElekSkyView>(*this, altitude_m, glm::normalize(sun_direction));
}

}  // namespace atmo
