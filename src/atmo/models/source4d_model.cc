#include "models/source4d_model.h"

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <mutex>
#include <shared_mutex>
#include <string>
#include <thread>

#include <oneapi/tbb/parallel_for.h>
#include <oneapi/tbb/task_arena.h>

#include "atmo/error.h"
#include "atmo/memory.h"
#include "cpu/sky_view_lookup.h"
#include "io/table_cache_file.h"
#include "models/model_options.h"
#include "physics/shared_parameters.h"

namespace atmo {
namespace {

// "AxBxCxD": `count` sizes, each in [lo, hi].
std::vector<int> ParseSizes(const std::string& key, const std::string& value, std::size_t count, int lo, int hi) {
  const auto fail = [&] {
    return Error("option " + key + "=" + value + ": expected " + std::to_string(count) + " integers in [" +
                 std::to_string(lo) + ", " + std::to_string(hi) + "] joined by 'x'");
  };
  std::vector<int> sizes;
  std::size_t begin = 0;
  while (true) {
    const std::size_t x = value.find('x', begin);
    try {
      sizes.push_back(ParseIntOption(key, value.substr(begin, x == std::string::npos ? std::string::npos : x - begin),
                                     lo, hi));
    } catch (const Error&) {
      throw fail();
    }
    if (x == std::string::npos) break;
    begin = x + 1;
  }
  if (sizes.size() != count) throw fail();
  return sizes;
}

}  // namespace

Source4dModelSettings Source4dModelSettings::FromOptions(const ModelOptions& options) {
  Source4dModelSettings s;
  cpu::Source4dSettings& t = s.tables;
  for (const auto& [key, value] : options) {
    if (key == "table") {
      const std::vector<int> n = ParseSizes(key, value, 4, 2, 512);
      t.r_size = n[0];
      t.mu_size = n[1];
      t.mu_s_size = n[2];
      t.phi_size = n[3];
      if (t.mu_s_size < shared::kSource4dMinSunZenithRows) {
        throw Error("option table=" + value + ": the sun-zenith axis (the third size) needs at least " +
                    std::to_string(shared::kSource4dMinSunZenithRows) + " rows, one per piece of its mapping");
      }
    } else if (key == "gather") {
      const std::vector<int> n = ParseSizes(key, value, 2, 3, 512);
      t.gather_zeniths = n[0];
      t.gather_azimuths = n[1];
    } else if (key == "gather_samples") {
      t.gather_samples = ParseIntOption(key, value, 2, 1000);
    } else if (key == "orders") {
      t.orders = ParseIntOption(key, value, 1, 32);
    } else if (key == "tail") {
      if (value != "on" && value != "off") throw Error("option tail=" + value + ": expected on or off");
      t.tail = value == "on";
    } else if (key == "samples") {
      s.samples = ParseIntOption(key, value, 2, 100000);
    } else if (key == "transmittance_lut") {
      t.transmittance_lut = ParseSizeOption(key, value, 2, 4096);
    } else if (key == "transmittance_samples") {
      t.transmittance_samples = ParseIntOption(key, value, 1, 100000);
    } else if (key == "sky_view") {
      if (value == "auto") {
        s.sky_view = Source4dModelSettings::SkyViewMode::kAuto;
      } else if (value == "on") {
        s.sky_view = Source4dModelSettings::SkyViewMode::kOn;
      } else if (value == "off") {
        s.sky_view = Source4dModelSettings::SkyViewMode::kOff;
      } else {
        throw Error("option sky_view=" + value + ": expected auto, on or off");
      }
    } else if (key == "sky_view_lut") {
      s.sky_view_lut = ParseSizeOption(key, value, 4, 8192);
      if (s.sky_view_lut.x % 2 != 0 || s.sky_view_lut.y % 2 != 0) {
        throw Error("option sky_view_lut=" + value +
                    ": the width and the height must be even (mirrored azimuths; sky and ground halves)");
      }
      if (double(s.sky_view_lut.x) * s.sky_view_lut.y > 16.0 * 1024 * 1024) {
        throw Error("option sky_view_lut=" + value + " has more than 2^24 texels (the limit)");
      }
    } else {
      throw Error("unknown option '" + key + "' for model source4d (known: table, gather, gather_samples, orders, "
                  "tail, samples, transmittance_lut, transmittance_samples, sky_view, sky_view_lut)");
    }
  }
  const double texels = double(t.r_size) * t.mu_size * t.mu_s_size * t.phi_size;
  if (texels > 64.0 * 1024 * 1024) {
    throw Error("option table: " + std::to_string(t.r_size) + "x" + std::to_string(t.mu_size) + "x" +
                std::to_string(t.mu_s_size) + "x" + std::to_string(t.phi_size) +
                " has more than 2^26 texels (the limit)");
  }
  const double rays = double(t.r_size) * t.mu_s_size * t.gather_zeniths * t.gather_azimuths;
  if (rays > 64.0 * 1024 * 1024) {
    throw Error("options table and gather: " + std::to_string(static_cast<long long>(rays)) +
                " gathering rays per order (r layers x sun zeniths x gathering directions) is more than 2^26 "
                "(the limit; the default is 670464)");
  }
  return s;
}

Source4dModel::Source4dModel(const AtmosphereParameters& parameters, const Source4dModelSettings& settings)
    : Model(parameters), settings_(settings) {
  Validate(parameters);
  if (parameters.geometry != Geometry::kSpherical) {
    throw Error("model source4d needs a spherical atmosphere; the half-space of preset '" + parameters.name +
                "' is the geometry of the simple model");
  }
  for (std::size_t b = 0; b < ChannelBatchCount(parameters.channel_count()); ++b) {
    Batch batch;
    batch.atmosphere = ToSharedParameters(parameters, b);
    batches_.push_back(std::move(batch));
  }
  // Peak memory (docs/reliability.md, "Memory"): ~200 bytes per cell measured at 16-32 r-rows
  // (mostly fixed costs), ~52 per cell at 64^4 (the 866 MB of table=64x64x64x64 an outside audit
  // measured); 64 per cell and batch of 3 channels plus 40 MB bounds both.
  const cpu::Source4dSettings& t = settings.tables;
  const double cells = static_cast<double>(t.r_size) * t.mu_size * t.mu_s_size * t.phi_size;
  CheckMemory("source4d tables of table=" + std::to_string(t.r_size) + "x" + std::to_string(t.mu_size) + "x" +
                  std::to_string(t.mu_s_size) + "x" + std::to_string(t.phi_size) + " at " +
                  std::to_string(parameters.channel_count()) + " channels",
              64.0 * cells * static_cast<double>(batches_.size()) + 40e6);
}

double Source4dModel::EstimatedPrecomputeSeconds() const {
  // Measured (docs/performance.md, "source4d on spectral atmospheres"; `atmo bench --model
  // source4d`): the default 16x24x48x8 table at 3 channels and 5 orders in 0.56 s on 2 threads,
  // 1.5 us of CPU per cell and order, the gathers dominating; the cost grows with the cells and
  // the orders, and each batch of 3 channels after the first adds 0.7 of the first's (the
  // batches share the rays' geometry: 15 channels took 3.8x as long as 3).
  const cpu::Source4dSettings& t = settings_.tables;
  const double cells = static_cast<double>(t.r_size) * t.mu_size * t.mu_s_size * t.phi_size;
  const double batches = 1.0 + kSource4dExtraBatchCost * (static_cast<double>(batches_.size()) - 1.0);
  const double cpu_seconds = 1.6e-6 * cells * std::max(t.orders, 1) * batches;
  return cpu_seconds / std::max(oneapi::tbb::this_task_arena::max_concurrency(), 1);
}

void Source4dModel::Precompute() {
  std::vector<shared::AtmosphereParameters> atmospheres;
  std::vector<cpu::Source4dTables*> tables;
  for (Batch& batch : batches_) {
    atmospheres.push_back(batch.atmosphere);
    tables.push_back(&batch.tables);
  }
  cpu::ComputeSource4dTables(atmospheres, settings_.tables, tables,
                             [&](std::string_view pass, double ms) { RecordPass(pass, ms); });
}

void Source4dModel::SetComputedTables(std::size_t b, cpu::Source4dTables tables) {
  const cpu::Source4dSettings& s = settings_.tables;
  const auto sized = [&](const shared::Texture3D& t) {
    return t.width == s.phi_size && t.height == s.mu_size && t.depth == s.r_size * s.mu_s_size;
  };
  const bool ok = tables.mu_s_size == s.mu_s_size && tables.transmittance.width == s.transmittance_lut.x &&
                  tables.transmittance.height == s.transmittance_lut.y && sized(tables.rayleigh) &&
                  sized(tables.mie) && tables.ground_irradiance.width == s.mu_s_size &&
                  tables.ground_irradiance.height == 1;
  if (!ok) throw Error("model source4d: computed tables of other sizes than its settings'");
  batches_.at(b).tables = std::move(tables);
}

bool Source4dModel::SaveTables(std::vector<unsigned char>& bytes) const {
  io::TableBytesWriter out;
  out.Int(static_cast<std::int64_t>(batches_.size()));
  for (const Batch& batch : batches_) {
    out.Int(batch.tables.mu_s_size);
    out.Texture(batch.tables.transmittance);
    out.Texture(batch.tables.rayleigh);
    out.Texture(batch.tables.mie);
    out.Texture(batch.tables.ground_irradiance);
  }
  bytes = std::move(out.bytes());
  return true;
}

bool Source4dModel::LoadTables(std::span<const unsigned char> bytes) {
  io::TableBytesReader in(bytes);
  std::int64_t count = 0;
  if (!in.Int(count) || count != static_cast<std::int64_t>(batches_.size())) return false;
  std::vector<cpu::Source4dTables> tables(batches_.size());
  for (cpu::Source4dTables& t : tables) {
    std::int64_t mu_s_size = 0;
    if (!in.Int(mu_s_size) || !in.Texture(t.transmittance) || !in.Texture(t.rayleigh) || !in.Texture(t.mie) ||
        !in.Texture(t.ground_irradiance)) {
      return false;
    }
    t.mu_s_size = static_cast<int>(std::clamp<std::int64_t>(mu_s_size, 0, 1 << 24));
  }
  if (!in.Finished()) return false;
  // Sizes checked for every batch before any is replaced.
  const std::vector<Batch> kept = batches_;
  try {
    for (std::size_t b = 0; b < tables.size(); ++b) SetComputedTables(b, std::move(tables[b]));
  } catch (const Error&) {
    batches_ = kept;
    return false;
  }
  return true;
}

namespace {

class Source4dSkyView final : public SkyView {
 public:
  Source4dSkyView(const Source4dModel& model, double altitude_m, const glm::dvec3& sun)
      : SkyView(altitude_m, sun, model.channel_count(), model.parameters().sun_angular_radius_rad),
        model_(model),
        r_(model.parameters().ground_radius_m + altitude_m),
        mu_s_(shared::ClampCosine(sun.z)) {
    horizon_nadir_angle_ = shared::GetHorizonNadirAngle(model.batches().front().atmosphere, r_);
    using Mode = Source4dModelSettings::SkyViewMode;
    table_serves_ = model.settings().sky_view != Mode::kOff && r_ <= model.batches().front().atmosphere.top_radius;
    if (table_serves_ && model.settings().sky_view == Mode::kOn) EnsureTables();
  }

  void Radiance(const glm::dvec3& view, std::span<double> out) const override {
    if (table_serves_ && model_.settings().sky_view == Source4dModelSettings::SkyViewMode::kOn) {
      {
        std::shared_lock<std::shared_mutex> lock(folded_mutex_);
        EnsureTexels(std::span<const glm::dvec3>(&view, 1));
      }
      const double azimuth = shared::GetAzimuthFromSun(view, sun_direction());
      ScatterBatches(model_.batches().size(), out, [&](std::size_t b) {
        return shared::GetSkyRadianceFromSkyView(model_.batches()[b].atmosphere, sky_view_[b], r_, view.z, azimuth);
      });
      return;
    }
    ScatterBatches(model_.batches().size(), out, [&](std::size_t b) {
      shared::vec3 ground;
      return Evaluate(model_.batches()[b], view, ground);
    });
  }

  void GroundRadiance(const glm::dvec3& view, std::span<double> out) const override {
    ScatterBatches(model_.batches().size(), out, [&](std::size_t b) {
      shared::vec3 ground;
      Evaluate(model_.batches()[b], view, ground);
      return ground;
    });
  }

  void Transmittance(const glm::dvec3& view, std::span<double> out) const override {
    ScatterBatches(model_.batches().size(), out, [&](std::size_t b) {
      const Source4dModel::Batch& batch = model_.batches()[b];
      return shared::GetViewTransmittance(batch.atmosphere, batch.tables.transmittance, r_,
                                          shared::ClampCosine(view.z));
    });
  }

  void SunDiscRadiance(const glm::dvec3& view, std::span<double> out) const override {
    const double nu = glm::dot(view, sun_direction());
    ScatterBatches(model_.batches().size(), out, [&](std::size_t b) {
      const Source4dModel::Batch& batch = model_.batches()[b];
      return shared::GetSunDiscRadiance(batch.atmosphere, batch.tables.transmittance, r_,
                                        shared::ClampCosine(view.z), nu);
    });
  }

  void ScatteringAlongSegment(const glm::dvec3& view, double distance_m, std::span<double> radiance,
                              std::span<double> transmittance) const override {
    const double nu = shared::ClampCosine(glm::dot(view, sun_direction()));
    const std::size_t n = channel_count();
    for (std::size_t b = 0; b < model_.batches().size(); ++b) {
      const Source4dModel::Batch& batch = model_.batches()[b];
      const cpu::Source4dTables& t = batch.tables;
      shared::vec3 segment_transmittance;
      const shared::vec3 l = shared::IntegrateSource4dRadiance(
          batch.atmosphere, t.transmittance, t.rayleigh, t.mie, t.mu_s_size, r_, shared::ClampCosine(view.z), mu_s_,
          nu, distance_m, model_.settings().samples, segment_transmittance);
      for (std::size_t c = 0; c < 3 && 3 * b + c < n; ++c) {
        radiance[3 * b + c] = l[c];
        transmittance[3 * b + c] = segment_transmittance[c];
      }
    }
  }

  // Both terms from one march per batch, or from the sky-view tables.
  void RadianceBatch(std::span<const glm::dvec3> views, const RadianceTerms& terms,
                     std::span<float> out) const override {
    const std::size_t n = channel_count();
    if (table_serves_) {
      {
        std::shared_lock<std::shared_mutex> lock(folded_mutex_);  // MarchTexel reads the folded weights
        EnsureTexels(views);
      }
      cpu::LookupSkyViewBatch(*this, terms.ground ? sky_and_ground_lookup_ : sky_lookup_,
                              terms.ground ? sky_and_ground_view_ : sky_view_, horizon_nadir_angle_, terms.sun_disc,
                              views, out);
      return;
    }
    oneapi::tbb::parallel_for(std::size_t{0}, views.size(), [&](std::size_t i) {
      const glm::dvec3& view = views[i];
      if (view.x == 0.0 && view.y == 0.0 && view.z == 0.0) return;
      std::vector<double> disc(n, 0.0);
      if (terms.sun_disc) SunDiscRadiance(view, disc);
      for (std::size_t b = 0; b < model_.batches().size(); ++b) {
        shared::vec3 ground;
        shared::vec3 l = Evaluate(model_.batches()[b], view, ground);
        if (terms.ground) l += ground;
        for (std::size_t c = 0; c < 3 && 3 * b + c < n; ++c) {
          out[i * n + 3 * b + c] = static_cast<float>(l[c] + disc[3 * b + c]);
        }
      }
    });
  }

  // The sky-view tables folded into three values per channel weight (RenderViewFolded): one float
  // lookup per pixel whatever the number of channels, as hillaire's. The folded tables follow the
  // texels as they are marched, for the last weights asked for.
  void RadianceBatchFolded(std::span<const glm::dvec3> views, const RadianceTerms& terms,
                           std::span<const glm::vec3> weights, std::span<float> out) const override {
    if (!table_serves_) {
      SkyView::RadianceBatchFolded(views, terms, weights, out);
      return;
    }
    const std::size_t n = channel_count();
    if (weights.size() != n) throw Error("RadianceBatchFolded needs one weight per channel");
    EnsureTables();
    {
      std::unique_lock<std::shared_mutex> lock(folded_mutex_);
      if (!std::equal(weights.begin(), weights.end(), folded_weights_.begin(), folded_weights_.end())) {
        folded_weights_.assign(weights.begin(), weights.end());
        // Every texel marched so far, folded with the new weights (the others are folded when marched).
        for (std::size_t i = 0; i < texel_state_.size(); ++i) {
          if (texel_state_[i].load(std::memory_order_acquire) == kMarched) FoldTexel(i);
        }
      }
    }
    std::shared_lock<std::shared_mutex> lock(folded_mutex_);
    EnsureTexels(views);
    cpu::LookupFoldedSkyViewBatch(*this, terms.ground ? folded_sky_and_ground_ : folded_sky_, weights, terms.sun_disc,
                                  views, out);
  }

  // The sky-view texels marched so far (for tests: a narrow view marches few).
  std::size_t texels_marched() const { return texels_marched_.load(); }

 private:
  static constexpr std::uint8_t kUnmarched = 0;
  static constexpr std::uint8_t kMarching = 1;
  static constexpr std::uint8_t kMarched = 2;

  // The sky-view tables of every batch, their float lookups and the texels' states, made once
  // (thread-safe), all texels zero and unmarched. The texels are marched when a lookup first
  // needs them (EnsureTexels): an image reads only the part of the table its camera sees (a 90°
  // perspective view about a seventh of it), and each texel is the same as an eager build's.
  void EnsureTables() const {
    std::call_once(tables_made_, [this] {
      const glm::ivec2 size = model_.settings().sky_view_lut;
      for (std::size_t b = 0; b < model_.batches().size(); ++b) {
        sky_view_.emplace_back(size.x, size.y, /*repeat=*/true);
        sky_and_ground_view_.emplace_back(size.x, size.y, /*repeat=*/true);
      }
      // Texel x looks at azimuth 2 pi x / width from the sun, so columns x and width - x are
      // mirror images: columns 0 .. width / 2 are marched, the others copied.
      texel_state_ = std::vector<std::atomic<std::uint8_t>>(static_cast<std::size_t>(size.y) * (size.x / 2 + 1));
      sky_lookup_ = cpu::MakeSkyViewLookup(sky_view_[0], horizon_nadir_angle_, sun_direction());
      sky_and_ground_lookup_ = cpu::MakeSkyViewLookup(sky_and_ground_view_[0], horizon_nadir_angle_, sun_direction());
      folded_sky_ = sky_lookup_;
      folded_sky_and_ground_ = sky_and_ground_lookup_;
    });
  }

  // Marches every texel that a lookup of `views` reads (the bilinear taps of the float lookup,
  // widened by 0.01 texel for the double-precision one). Threads that need a texel another one
  // is marching wait for it. The caller holds folded_mutex_ shared.
  void EnsureTexels(std::span<const glm::dvec3> views) const {
    EnsureTables();
    if (texels_marched_.load(std::memory_order_acquire) == texel_state_.size()) return;  // all of them
    const glm::ivec2 size = model_.settings().sky_view_lut;
    const int half_width = size.x / 2;
    constexpr int kChunk = 256;
    int previous[4] = {-1, -1, -1, -1};  // the last direction's taps: neighbours in a row mostly share them
    float x[kChunk], y[kChunk], z[kChunk], s[kChunk], t[kChunk];
    for (std::size_t begin = 0; begin < views.size(); begin += kChunk) {
      const int count = static_cast<int>(std::min<std::size_t>(kChunk, views.size() - begin));
      for (int i = 0; i < count; ++i) {
        const glm::dvec3& v = views[begin + static_cast<std::size_t>(i)];
        x[i] = static_cast<float>(v.x);
        y[i] = static_cast<float>(v.y);
        z[i] = static_cast<float>(v.z);
      }
      cpu::GetSkyViewTexelCoordinatesRow(sky_lookup_, x, y, z, count, s, t);
      for (int i = 0; i < count; ++i) {
        const glm::dvec3& v = views[begin + static_cast<std::size_t>(i)];
        if (v.x == 0.0 && v.y == 0.0 && v.z == 0.0) continue;  // nothing seen
        const int s0 = static_cast<int>(std::floor(s[i] - 0.01f));
        const int s1 = static_cast<int>(std::floor(s[i] + 0.01f)) + 1;
        const int t0 = std::max(static_cast<int>(std::floor(t[i] - 0.01f)), 0);
        const int t1 = std::min(static_cast<int>(std::floor(t[i] + 0.01f)) + 1, size.y - 1);
        if (s0 == previous[0] && s1 == previous[1] && t0 == previous[2] && t1 == previous[3]) continue;
        previous[0] = s0;
        previous[1] = s1;
        previous[2] = t0;
        previous[3] = t1;
        for (int row = t0; row <= t1; ++row) {
          for (int column = s0; column <= s1; ++column) {
            const int wrapped = ((column % size.x) + size.x) % size.x;
            const int marched = wrapped <= half_width ? wrapped : size.x - wrapped;
            EnsureTexel(marched, row);
          }
        }
      }
    }
  }

  void EnsureTexel(int x, int y) const {
    const std::size_t i = static_cast<std::size_t>(y) * (model_.settings().sky_view_lut.x / 2 + 1) + x;
    std::atomic<std::uint8_t>& state = texel_state_[i];
    if (state.load(std::memory_order_acquire) == kMarched) return;
    std::uint8_t expected = kUnmarched;
    if (state.compare_exchange_strong(expected, kMarching, std::memory_order_acq_rel)) {
      MarchTexel(x, y);
      state.store(kMarched, std::memory_order_release);
      texels_marched_.fetch_add(1, std::memory_order_acq_rel);
      return;
    }
    while (state.load(std::memory_order_acquire) != kMarched) std::this_thread::yield();
  }

  // Texel (x, y) of every batch's tables (x <= width / 2) and its mirror column, the scattered
  // radiance of its direction and the same with the lit ground added in the ground half; then
  // its copies in the float lookups (three channels) and the folded ones. The folded weights are
  // read under the caller's shared lock (RadianceBatchFolded) or are not yet set.
  void MarchTexel(int x, int y) const {
    const glm::ivec2 size = model_.settings().sky_view_lut;
    const auto& batches = model_.batches();
    for (std::size_t b = 0; b < batches.size(); ++b) {
      const cpu::Source4dTables& t = batches[b].tables;
      shared::vec3 ground;
      const shared::vec3 l = shared::ComputeSource4dSkyViewTexel(
          batches[b].atmosphere, t.transmittance, t.rayleigh, t.mie, t.ground_irradiance, t.mu_s_size,
          shared::ivec2(size.x, size.y), shared::vec2(x + 0.5, y + 0.5), r_, mu_s_, model_.settings().samples, ground);
      for (const int column : {x, (size.x - x) % size.x}) {
        sky_view_[b].at(column, y) = glm::vec3(l);
        sky_and_ground_view_[b].at(column, y) = glm::vec3(l + ground);
      }
    }
    for (const int column : {x, (size.x - x) % size.x}) {
      const std::size_t texel = static_cast<std::size_t>(y) * size.x + column;
      sky_lookup_.texels[texel] = glm::vec4(sky_view_[0].texels[texel], 0.0f);
      sky_and_ground_lookup_.texels[texel] = glm::vec4(sky_and_ground_view_[0].texels[texel], 0.0f);
    }
    if (!folded_weights_.empty()) FoldTexel(static_cast<std::size_t>(y) * (size.x / 2 + 1) + x);
  }

  // The folded lookups' copies of marched texel `i` (its index in texel_state_) and its mirror.
  void FoldTexel(std::size_t i) const {
    const glm::ivec2 size = model_.settings().sky_view_lut;
    const int y = static_cast<int>(i / static_cast<std::size_t>(size.x / 2 + 1));
    const int x = static_cast<int>(i % static_cast<std::size_t>(size.x / 2 + 1));
    const std::size_t n = channel_count();
    for (const int column : {x, (size.x - x) % size.x}) {
      const std::size_t texel = static_cast<std::size_t>(y) * size.x + column;
      glm::vec3 sky(0.0f);
      glm::vec3 sky_and_ground(0.0f);
      for (std::size_t c = 0; c < n; ++c) {
        const int k = static_cast<int>(c % 3);
        sky += folded_weights_[c] * sky_view_[c / 3].texels[texel][k];
        sky_and_ground += folded_weights_[c] * sky_and_ground_view_[c / 3].texels[texel][k];
      }
      folded_sky_.texels[texel] = glm::vec4(sky, 0.0f);
      folded_sky_and_ground_.texels[texel] = glm::vec4(sky_and_ground, 0.0f);
    }
  }

  shared::vec3 Evaluate(const Source4dModel::Batch& batch, const glm::dvec3& view, shared::vec3& ground) const {
    const cpu::Source4dTables& t = batch.tables;
    const double nu = shared::ClampCosine(glm::dot(view, sun_direction()));
    return shared::GetSource4dRadiance(batch.atmosphere, t.transmittance, t.rayleigh, t.mie, t.ground_irradiance,
                                       t.mu_s_size, r_, shared::ClampCosine(view.z), mu_s_, nu,
                                       model_.settings().samples, ground);
  }

  const Source4dModel& model_;
  double r_;
  double mu_s_;
  double horizon_nadir_angle_ = 0.0;
  bool table_serves_ = false;  // sky_view on or auto, and the observer inside the atmosphere
  // Made by EnsureTables, once; their texels marched by EnsureTexels as lookups need them.
  mutable std::once_flag tables_made_;
  mutable std::vector<shared::Texture2D> sky_view_;             // one per batch
  mutable std::vector<shared::Texture2D> sky_and_ground_view_;  // sky_view_ plus the lit ground, for images
  mutable std::vector<std::atomic<std::uint8_t>> texel_state_;  // per marched texel: kUnmarched, kMarching, kMarched
  mutable std::atomic<std::size_t> texels_marched_{0};
  mutable cpu::SkyViewLookup sky_lookup_;  // float frame-kernel copies (the first batch; read for three channels)
  mutable cpu::SkyViewLookup sky_and_ground_lookup_;
  // The folded lookups of RadianceBatchFolded and their weights (empty: none asked for yet).
  mutable std::shared_mutex folded_mutex_;
  mutable std::vector<glm::vec3> folded_weights_;
  mutable cpu::SkyViewLookup folded_sky_;
  mutable cpu::SkyViewLookup folded_sky_and_ground_;
};

}  // namespace

std::size_t Source4dModel::SkyViewTexelsMarched(const SkyView& view) {
  const auto* source4d = dynamic_cast<const Source4dSkyView*>(&view);
  return source4d != nullptr ? source4d->texels_marched() : 0;
}

std::unique_ptr<SkyView> Source4dModel::View(double altitude_m, const glm::dvec3& sun_direction) const {
  if (!std::isfinite(altitude_m) || altitude_m < 0.0) {
    throw Error("altitude_m must be finite and >= 0 for model source4d (got " + std::to_string(altitude_m) + ")");
  }
  CheckDirection(sun_direction, "the sun direction");
  return std::make_unique<Source4dSkyView>(*this, altitude_m, glm::normalize(sun_direction));
}

}  // namespace atmo
