#include "atmo/model.h"

#include <algorithm>
#include <charconv>
#include <cmath>
#include <chrono>
#include <cstdio>
#include <optional>
#include <string>
#include <vector>

#include <oneapi/tbb/task_arena.h>

#include "atmo/error.h"
#include "atmo/table_cache.h"
#include "io/table_cache_file.h"
#include "models/elek_model.h"
#include "models/hillaire_model.h"
#include "models/reference_model.h"
#include "models/simple_model.h"
#include "models/source4d_model.h"

namespace atmo {
namespace {

// 95 -> "1 min 35 s", 7.4 -> "7 s".
std::string FormatDuration(double seconds) {
  char text[64];
  if (seconds < 60.0) {
    std::snprintf(text, sizeof text, "%.0f s", seconds);
  } else if (seconds < 3600.0) {
    std::snprintf(text, sizeof text, "%d min %02d s", static_cast<int>(seconds / 60.0),
                  static_cast<int>(std::fmod(seconds, 60.0)));
  } else {
    std::snprintf(text, sizeof text, "%.1f h", seconds / 3600.0);
  }
  return text;
}

}  // namespace

void Model::RecordPass(std::string_view pass, double ms) const {
  {
    std::lock_guard<std::mutex> lock(timings_mutex_);
    timings_.Add(pass, ms);
  }
  if (announce_passes_) {
    const double in_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - progress_start_).count();
    char text[160];
    std::snprintf(text, sizeof text, "%.*s done, %.0f s in", static_cast<int>(pass.size()), pass.data(), in_s);
    progress::Send(text);
  }
}

void SkyView::RadianceEstimate(const glm::dvec3& view, std::span<double> radiance,
                               std::span<double> standard_error) const {
  Radiance(view, radiance);
  std::fill(standard_error.begin(), standard_error.end(), 0.0);
}

void SkyView::GroundRadiance(const glm::dvec3&, std::span<double> out) const {
  std::fill(out.begin(), out.end(), 0.0);
}

void SkyView::RadianceBatch(std::span<const glm::dvec3> views, const RadianceTerms& terms, std::span<float> out) const {
  const std::size_t n = channel_count();
  std::vector<double> radiance(n);
  std::vector<double> term(n);
  for (std::size_t i = 0; i < views.size(); ++i) {
    const glm::dvec3& view = views[i];
    if (view.x == 0.0 && view.y == 0.0 && view.z == 0.0) continue;
    Radiance(view, radiance);
    if (terms.sun_disc) {
      SunDiscRadiance(view, term);
      for (std::size_t c = 0; c < n; ++c) radiance[c] += term[c];
    }
    if (terms.ground) {
      GroundRadiance(view, term);
      for (std::size_t c = 0; c < n; ++c) radiance[c] += term[c];
    }
    for (std::size_t c = 0; c < n; ++c) out[i * n + c] = static_cast<float>(radiance[c]);
  }
}

void SkyView::RadianceBatchFolded(std::span<const glm::dvec3> views, const RadianceTerms& terms,
                                  std::span<const glm::vec3> weights, std::span<float> out) const {
  const std::size_t n = channel_count();
  if (weights.size() != n) throw Error("RadianceBatchFolded needs one weight per channel");
  std::vector<float> channels(views.size() * n);
  RadianceBatch(views, terms, channels);
  for (std::size_t i = 0; i < views.size(); ++i) {
    glm::vec3 sum(0.0f);
    for (std::size_t c = 0; c < n; ++c) sum += weights[c] * channels[i * n + c];
    for (int k = 0; k < 3; ++k) out[3 * i + k] = sum[k];
  }
}

void SkyView::ScatteringAlongSegment(const glm::dvec3&, double, std::span<double>, std::span<double>) const {
  throw Error("this model does not provide aerial perspective");
}

std::vector<std::string> ModelNames() { return {"elek", "hillaire", "reference", "simple", "source4d"}; }

std::unique_ptr<Model> CreateModel(std::string_view name, const AtmosphereParameters& parameters,
                                   const ModelOptions& options) {
  // "seed" is common to every model; deterministic models ignore it.
  ModelOptions model_options = options;
  if (const auto seed = model_options.find("seed"); seed != model_options.end()) {
    const std::string& text = seed->second;
    // Up to 2^64 - 1 = 18446744073709551615 (20 digits; 19 refused valid seeds).
    std::uint64_t value = 0;
    const auto [end, error] = std::from_chars(text.data(), text.data() + text.size(), value);
    if (text.empty() || text.find_first_not_of("0123456789") != std::string::npos || error != std::errc() ||
        end != text.data() + text.size()) {
      throw Error("option seed=" + text + ": expected an integer in [0, 18446744073709551615]");
    }
  }
  std::unique_ptr<Model> model;
  if (name == "elek") {
    model_options.erase("seed");
    model = std::make_unique<ElekModel>(parameters, ElekSettings::FromOptions(model_options));
  } else if (name == "hillaire") {
    model_options.erase("seed");
    model = std::make_unique<HillaireModel>(parameters, HillaireSettings::FromOptions(model_options));
  } else if (name == "reference") {
    model = std::make_unique<ReferenceModel>(parameters, ReferenceSettings::FromOptions(model_options));
  } else if (name == "source4d") {
    model_options.erase("seed");
    model = std::make_unique<Source4dModel>(parameters, Source4dModelSettings::FromOptions(model_options));
  } else if (name == "simple") {
    model_options.erase("seed");
    model = std::make_unique<SimpleModel>(parameters, model_options);
  } else {
    std::string known;
    for (const std::string& n : ModelNames()) known += (known.empty() ? "" : ", ") + n;
    throw Error("unknown model '" + std::string(name) + "' (known: " + known + ")");
  }
  // Tables kept by an earlier process (include/atmo/table_cache.h) instead of a precomputation.
  std::optional<TableCache> cache = GetTableCache();
  if (cache && cache->folder.empty() && cache->shipped.empty()) cache.reset();
  std::string cache_key;
  if (cache) {
    cache_key = io::TableCacheKey(name, model_options, parameters);
    const auto start = std::chrono::steady_clock::now();
    const std::optional<io::CachedTables> kept = io::ReadCachedTables(*cache, cache_key);
    if (kept && model->LoadTables(kept->payload)) {
      model->RecordPass("table_cache_read",
                        std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count());
      return model;
    }
  }
  // Long work is announced before it starts, and each of its passes as it ends.
  const double estimate = model->EstimatedPrecomputeSeconds();
  if (progress::Wanted(estimate)) {
    char text[200];
    std::snprintf(text, sizeof text, "%s precomputation: about %s on %d threads (an estimate)",
                  std::string(model->name()).c_str(), FormatDuration(estimate).c_str(),
                  oneapi::tbb::this_task_arena::max_concurrency());
    progress::Send(text);
    model->progress_start_ = std::chrono::steady_clock::now();
    model->announce_passes_ = true;
  }
  model->Precompute();
  model->announce_passes_ = false;
  std::vector<unsigned char> bytes;
  if (cache && !cache->folder.empty() && model->SaveTables(bytes)) {
    const std::string why = io::WriteCachedTables(*cache, cache_key, bytes);
    if (!why.empty()) {
      progress::Send("table cache: the " + std::string(model->name()) + " tables were not kept in '" +
                     cache->folder.string() + "': " + why);
    }
  }
  return model;
}

glm::dvec3 DirectionFromZenithAzimuth(double zenith_rad, double azimuth_rad) {
  return {std::sin(zenith_rad) * std::sin(azimuth_rad), std::sin(zenith_rad) * std::cos(azimuth_rad),
          std::cos(zenith_rad)};
}

}  // namespace atmo
