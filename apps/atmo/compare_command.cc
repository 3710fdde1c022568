// `atmo compare`: a model against a reference model on a grid of configurations (docs/design.md §5).
//
// Both models are made from the same parameters (--preset / --config), each with its own options
// (--option for the model under test M, --against-option for the reference R; --seed for both).
// For every configuration (altitude, sun zenith, view zenith, azimuth) and channel it computes the
// signed relative error e = (M - R) / R (atmo::RelativeError), and, where either side reports a
// standard error, z = (M - R) / sqrt(se_M^2 + se_R^2) (atmo::ErrorInStandardErrors).
//
// Rows whose reference radiance is at most `floor` times the largest reference radiance of their
// sky (same altitude, sun zenith and channel) are reported in the CSV (included = 0) but left out
// of the relative statistics: the sky seen from 100 km looking up into space (R = 0), the air
// above an observer at 50 km in the Earth's shadow (R ~ 1e-10). The statistics (median, p95, max
// |e|, rel_mae, mean e: atmo::SummarizeRelativeErrors) are printed overall, per channel, per
// sun-zenith band and per altitude; --csv, --json and --image write the details.
#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <functional>
#include <limits>
#include <map>
#include <mutex>
#include <numbers>
#include <string>
#include <utility>
#include <vector>

#include <glm/glm.hpp>
#include <nlohmann/json.hpp>
#include <oneapi/tbb/parallel_for.h>

#include "atmo/error.h"
#include "atmo/image.h"
#include "atmo/metrics.h"
#include "atmo/parameters.h"
#include "commands.h"
#include "grid.h"
#include "progress_bar.h"

namespace atmo::cli {

namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

// ---------------------------------------------------------------------------------------------
// The standard grid (docs/design.md §5): every combination of these values, 5 x 7 x 27 x 5 = 4725
// configurations. View zeniths are dense around the horizontal (90°); the planet's horizon dips
// below it with altitude (by acos(r_ground / r_observer): 3.2° at 10 km, 7.1° at 50 km, 10.1° at
// 100 km on `earth`), where 95° and 100° sample it. At view zenith 0 and 180 (and sun zenith 0)
// the azimuth changes nothing; those rows repeat, as the grid is a plain product.

const std::vector<double> kStandardAltitudesM = {0.0, 1000.0, 10000.0, 50000.0, 100000.0};
const std::vector<double> kStandardSunZenithsDeg = {0.0, 30.0, 60.0, 80.0, 90.0, 95.0, 100.0};
const std::vector<double> kStandardViewZenithsDeg = {0.0,  10.0, 20.0, 30.0, 40.0,  50.0,  60.0,  70.0,  80.0,
                                                     85.0, 88.0, 89.0, 89.5, 90.0,  90.5,  91.0,  92.0,  95.0,
                                                     100.0, 110.0, 120.0, 130.0, 140.0, 150.0, 160.0, 170.0, 180.0};
const std::vector<double> kStandardAzimuthsDeg = {0.0, 45.0, 90.0, 135.0, 180.0};

std::vector<SamplePoint> ProductGrid(const std::vector<double>& altitudes_m, const std::vector<double>& sun_zeniths_deg,
                                     const std::vector<double>& view_zeniths_deg, const std::vector<double>& azimuths_deg) {
  std::vector<SamplePoint> points;
  for (double altitude : altitudes_m) {
    for (double sun : sun_zeniths_deg) {
      for (double view : view_zeniths_deg) {
        for (double azimuth : azimuths_deg) points.push_back({altitude, sun, view, azimuth, ""});
      }
    }
  }
  return points;
}

// The twilight grid: the standard grid's altitudes, views and azimuths with the sun from the
// horizontal to the end of nautical twilight (108°) every 2°: 5 x 10 x 27 x 5 = 6750
// configurations. Where the sun is below the horizon the sky is lit by light that scattered high
// in the still-sunlit air; multiple scattering carries all of it in the Earth's shadow.
const std::vector<double> kTwilightSunZenithsDeg = {90.0, 92.0, 94.0, 96.0, 98.0, 100.0, 102.0, 104.0, 106.0, 108.0};

// The space grid: observers from 100 to 1000 km, which see the atmosphere as a bright limb
// around the planet. A fixed list of view zeniths would miss the limb, which moves with
// altitude, so the views are set per altitude by the ray's tangent altitude h_t (the closest
// approach to the planet's centre, r sin(theta) = r_ground + h_t for theta > 90°): 11 tangent
// altitudes from 80 km to 0.5 km across the limb, then 5 views that meet the ground at angles
// past the planet's horizon (0.25° to 30°) and the nadir. Views above the limb see only space
// (R = 0, below the floor) and are left out. Tangent altitudes above the atmosphere's top are
// dropped. 5 altitudes x 7 sun zeniths x 17 views x 5 azimuths = 2975 configurations on `earth`.
const std::vector<double> kSpaceAltitudesM = {100e3, 200e3, 400e3, 700e3, 1000e3};
const std::vector<double> kSpaceSunZenithsDeg = {0.0, 30.0, 60.0, 80.0, 90.0, 100.0, 110.0};
const std::vector<double> kSpaceTangentAltitudesM = {80e3, 60e3, 40e3, 30e3, 20e3, 15e3, 10e3, 5e3, 2e3, 1e3, 500.0};
const std::vector<double> kSpaceBelowHorizonDeg = {0.25, 1.0, 3.0, 10.0, 30.0};

std::vector<SamplePoint> SpaceGrid(const AtmosphereParameters& parameters) {
  if (parameters.geometry != Geometry::kSpherical) {
    throw Error("--grid space needs a spherical planet (this atmosphere is a flat half-space)");
  }
  const double ground = parameters.ground_radius_m;
  const double top = parameters.top_radius_m;
  constexpr double kDegrees = 180.0 / std::numbers::pi;
  std::vector<SamplePoint> points;
  for (double altitude : kSpaceAltitudesM) {
    const double r = ground + altitude;
    std::vector<double> views;
    for (double tangent : kSpaceTangentAltitudesM) {
      if (ground + tangent >= std::min(r, top)) continue;
      views.push_back(180.0 - std::asin((ground + tangent) / r) * kDegrees);
    }
    const double horizon = 180.0 - std::asin(ground / r) * kDegrees;
    for (double below : kSpaceBelowHorizonDeg) views.push_back(std::min(180.0, horizon + below));
    views.push_back(180.0);
    for (double sun : kSpaceSunZenithsDeg) {
      for (double view : views) {
        for (double azimuth : kStandardAzimuthsDeg) points.push_back({altitude, sun, view, azimuth, ""});
      }
    }
  }
  return points;
}

// `--grid NAME|IN.csv`: a named grid, or a file (write ./standard for a file of that name).
std::vector<SamplePoint> GridFor(const std::string& grid, const AtmosphereParameters& parameters) {
  if (grid == "standard") {
    return ProductGrid(kStandardAltitudesM, kStandardSunZenithsDeg, kStandardViewZenithsDeg, kStandardAzimuthsDeg);
  }
  if (grid == "twilight") {
    return ProductGrid(kStandardAltitudesM, kTwilightSunZenithsDeg, kStandardViewZenithsDeg, kStandardAzimuthsDeg);
  }
  if (grid == "space") return SpaceGrid(parameters);
  return ReadGrid(grid);
}

bool IsNamedGrid(const std::string& grid) { return grid == "standard" || grid == "twilight" || grid == "space"; }

// ---------------------------------------------------------------------------------------------
// Sun-zenith bands of the summary. A configuration belongs to exactly one.

struct SunBand {
  const char* key;         // JSON key
  const char* label;       // table row
  const char* definition;  // in words, for the JSON
  double min_deg;
  double max_deg;
};

const SunBand kSunBands[] = {
    // The sun's centre above the horizontal plane.
    {"sun_up", "sun up (<90)", "sun zenith < 90", 0.0, 90.0},
    // Civil twilight (to 96) and the first part of nautical twilight; 90 itself is sunset.
    {"twilight", "twilight (90-100)", "90 <= sun zenith <= 100", 90.0, 100.0},
    {"night", "night (>100)", "sun zenith > 100", 100.0, 180.0},
};

int BandOf(double sun_zenith_deg) {
  if (sun_zenith_deg < 90.0) return 0;
  if (sun_zenith_deg <= 100.0) return 1;
  return 2;
}

// ---------------------------------------------------------------------------------------------

// The options a model is created with: --option / --against-option plus the seed (as
// CreateModelFor does for one model).
ModelOptions EffectiveOptions(const std::vector<std::string>& options, const CommonOptions& common) {
  ModelOptions parsed = ParseModelOptions(options);
  if (common.seed_given) {
    if (parsed.count("seed") != 0) throw Error("give the seed once: --seed or --option seed=N");
    parsed["seed"] = std::to_string(common.seed);
  }
  return parsed;
}

// "hillaire" or "hillaire (multiple_scattering_directions=2, seed=1)".
std::string Describe(const std::string& model, const ModelOptions& options) {
  if (options.empty()) return model;
  std::string text = model + " (";
  bool first = true;
  for (const auto& [key, value] : options) {
    if (!first) text += ", ";
    text += key + "=" + value;
    first = false;
  }
  return text + ")";
}

// A relative error as a percentage for the table: "1.23%", "0.0123%", "1.2e-05%"; "-" for NaN.
std::string Percent(double e) {
  if (std::isnan(e)) return "-";
  const double v = 100.0 * e;
  if (v == 0.0) return "0%";
  if (std::isinf(v)) return v > 0 ? "inf" : "-inf";
  if (std::abs(v) >= 0.01) return Format("%.3g%%", v);
  return Format("%.2g%%", v);
}

std::string Number(double x) {
  if (std::isnan(x)) return "-";
  return Format("%.3g", x);
}

// What both models give for one configuration and channel.
struct Row {
  double radiance = 0.0;
  double standard_error = 0.0;
  double reference = 0.0;
  double reference_standard_error = 0.0;
  double relative_error = 0.0;
  double z = kNaN;  // error in standard errors; NaN without standard errors
  bool included = false;
};

// The configurations grouped by sky (altitude, sun zenith), in the order they first appear.
struct Sky {
  double altitude_m;
  double sun_zenith_deg;
  std::vector<std::size_t> points;
};

std::vector<Sky> GroupBySky(const std::vector<SamplePoint>& points) {
  std::vector<Sky> skies;
  std::map<std::pair<double, double>, std::size_t> index;
  for (std::size_t p = 0; p < points.size(); ++p) {
    const std::pair<double, double> key(points[p].altitude_m, points[p].sun_zenith_deg);
    auto [it, inserted] = index.emplace(key, skies.size());
    if (inserted) skies.push_back({key.first, key.second, {}});
    skies[it->second].points.push_back(p);
  }
  return skies;
}

glm::dvec3 SunAtZenith(double sun_zenith_deg) {
  return DirectionFromZenithAzimuth(glm::radians(sun_zenith_deg), 0.0);
}

// Evaluates both models on every point: rows[point * channels + channel]. `progress(done, total)`
// is called as configurations complete, one call at a time (a busy reporter is skipped, not waited for).
//
// R comes from `reference`, or, where it is null, from `samples` (the rows of `atmo sample`, for
// the same points), whose transmittance must then agree with the model's to kTransmittanceTolerance
// where it is above kTransmittanceFloor: a file sampled from other media is refused.
constexpr double kTransmittanceTolerance = 0.02;
constexpr double kTransmittanceFloor = 0.05;

std::vector<Row> Evaluate(const Model& model, const Model* reference, const SampleTable* samples,
                          const std::vector<SamplePoint>& points, double floor,
                          const std::function<void(std::size_t, std::size_t)>& progress) {
  const std::size_t channels = model.channel_count();
  std::atomic<std::size_t> done{0};
  std::mutex reporting;
  std::vector<Row> rows(points.size() * channels);
  const std::vector<Sky> skies = GroupBySky(points);
  oneapi::tbb::parallel_for(std::size_t{0}, skies.size(), [&](std::size_t s) {
    const Sky& sky = skies[s];
    const glm::dvec3 sun = SunAtZenith(sky.sun_zenith_deg);
    std::unique_ptr<SkyView> view;
    std::unique_ptr<SkyView> reference_view;
    try {
      view = model.View(sky.altitude_m, sun);
      if (reference != nullptr) reference_view = reference->View(sky.altitude_m, sun);
    } catch (const Error& error) {
      const std::string& where = points[sky.points.front()].location;
      throw Error((where.empty() ? "" : where + ": ") + error.what());
    }
    oneapi::tbb::parallel_for(std::size_t{0}, sky.points.size(), [&](std::size_t i) {
      const SamplePoint& point = points[sky.points[i]];
      const glm::dvec3 direction =
          DirectionFromZenithAzimuth(glm::radians(point.view_zenith_deg), glm::radians(point.azimuth_deg));
      std::vector<double> l(channels), se(channels, 0.0), r(channels), r_se(channels, 0.0);
      view->RadianceEstimate(direction, l, se);
      const std::size_t first = sky.points[i] * channels;
      if (reference_view) {
        reference_view->RadianceEstimate(direction, r, r_se);
      } else {
        std::vector<double> t(channels);
        view->Transmittance(direction, t);
        for (std::size_t c = 0; c < channels; ++c) {
          r[c] = samples->radiance[first + c];
          r_se[c] = samples->standard_error[first + c];
          const double file_t = samples->transmittance[first + c];
          if (std::max(t[c], file_t) > kTransmittanceFloor && !(std::fabs(t[c] - file_t) <= kTransmittanceTolerance)) {
            throw Error(Format("%s: transmittance %.4g where --model gives %.4g: the samples were taken with other "
                               "parameters (--preset/--config)",
                               point.location.c_str(), file_t, t[c]));
          }
        }
      }
      for (std::size_t c = 0; c < channels; ++c) {
        Row& row = rows[sky.points[i] * channels + c];
        row.radiance = l[c];
        row.standard_error = se[c];
        row.reference = r[c];
        row.reference_standard_error = r_se[c];
        row.relative_error = RelativeError(l[c], r[c]);
        row.z = ErrorInStandardErrors(l[c], r[c], se[c], r_se[c]);
      }
      const std::size_t finished = done.fetch_add(1, std::memory_order_relaxed) + 1;
      if (reporting.try_lock()) {
        progress(finished, points.size());
        reporting.unlock();
      }
    });
    // The floor: relative to the brightest reference value of this sky, per channel.
    for (std::size_t c = 0; c < channels; ++c) {
      double brightest = 0.0;
      for (std::size_t p : sky.points) brightest = std::max(brightest, rows[p * channels + c].reference);
      for (std::size_t p : sky.points) {
        Row& row = rows[p * channels + c];
        row.included = row.reference > 0.0 && row.reference > floor * brightest;
      }
    }
  });
  return rows;
}

// One line of the summary: the included rows of a group.
struct GroupSummary {
  std::string key;
  std::string label;
  std::size_t excluded = 0;
  RelativeErrorSummary errors;
  RelativeErrorSummary z;  // of the errors in standard errors, where defined (count 0 otherwise)
};

GroupSummary Summarize(std::string key, std::string label, const std::vector<Row>& rows,
                       const std::vector<std::size_t>& selected) {
  GroupSummary summary{std::move(key), std::move(label), 0, {}, {}};
  std::vector<double> errors, z;
  for (std::size_t i : selected) {
    const Row& row = rows[i];
    if (!row.included) {
      ++summary.excluded;
      continue;
    }
    errors.push_back(row.relative_error);
    if (!std::isnan(row.z)) z.push_back(row.z);
  }
  summary.errors = SummarizeRelativeErrors(errors);
  summary.z = SummarizeRelativeErrors(z);
  return summary;
}

std::string AltitudeLabel(double altitude_m) { return Format("altitude %.10g m", altitude_m); }

struct Summaries {
  GroupSummary overall;
  std::vector<GroupSummary> channels;
  std::vector<GroupSummary> bands;      // non-empty bands only
  std::vector<int> band_indices;        // kSunBands index of each entry of `bands`
  std::vector<GroupSummary> altitudes;  // ascending altitude
  std::vector<double> altitude_values;
};

Summaries SummarizeAll(const std::vector<SamplePoint>& points, const std::vector<Row>& rows,
                       const std::vector<double>& wavelengths_nm) {
  const std::size_t channels = wavelengths_nm.size();
  std::vector<std::size_t> all(rows.size());
  for (std::size_t i = 0; i < rows.size(); ++i) all[i] = i;

  Summaries s{Summarize("overall", "overall", rows, all), {}, {}, {}, {}, {}};
  for (std::size_t c = 0; c < channels; ++c) {
    std::vector<std::size_t> selected;
    for (std::size_t p = 0; p < points.size(); ++p) selected.push_back(p * channels + c);
    s.channels.push_back(Summarize(Format("%.10g", wavelengths_nm[c]), Format("%.10g nm", wavelengths_nm[c]),
                                   rows, selected));
  }
  for (int b = 0; b < static_cast<int>(std::size(kSunBands)); ++b) {
    std::vector<std::size_t> selected;
    for (std::size_t p = 0; p < points.size(); ++p) {
      if (BandOf(points[p].sun_zenith_deg) != b) continue;
      for (std::size_t c = 0; c < channels; ++c) selected.push_back(p * channels + c);
    }
    if (selected.empty()) continue;
    s.bands.push_back(Summarize(kSunBands[b].key, kSunBands[b].label, rows, selected));
    s.band_indices.push_back(b);
  }
  std::map<double, std::vector<std::size_t>> by_altitude;
  for (std::size_t p = 0; p < points.size(); ++p) {
    for (std::size_t c = 0; c < channels; ++c) by_altitude[points[p].altitude_m].push_back(p * channels + c);
  }
  for (const auto& [altitude, selected] : by_altitude) {
    s.altitudes.push_back(Summarize(Format("%.10g", altitude), AltitudeLabel(altitude), rows, selected));
    s.altitude_values.push_back(altitude);
  }
  return s;
}

// The index of the included row with the largest |e|, or rows.size() when none is included.
std::size_t WorstRow(const std::vector<Row>& rows) {
  std::size_t worst = rows.size();
  for (std::size_t i = 0; i < rows.size(); ++i) {
    if (!rows[i].included) continue;
    if (worst == rows.size() || std::abs(rows[i].relative_error) > std::abs(rows[worst].relative_error)) worst = i;
  }
  return worst;
}

// The summary's rows as cells: one per group (overall, channels, sun-zenith bands, altitudes), in
// the columns of the header below; the z columns only `with_z`.
std::vector<std::vector<std::string>> TableRows(const Summaries& s, bool with_z) {
  std::vector<std::vector<std::string>> rows;
  const auto add = [&](const GroupSummary& g) {
    std::vector<std::string> row = {g.label,
                                    std::to_string(g.errors.count),
                                    std::to_string(g.excluded),
                                    Percent(g.errors.median_abs),
                                    Percent(g.errors.p95_abs),
                                    Percent(g.errors.max_abs),
                                    Percent(g.errors.rel_mae),
                                    Percent(g.errors.mean)};
    if (with_z) {
      row.push_back(Number(g.z.median_abs));
      row.push_back(Number(g.z.p95_abs));
    }
    rows.push_back(std::move(row));
  };
  add(s.overall);
  for (const GroupSummary& g : s.channels) add(g);
  for (const GroupSummary& g : s.bands) add(g);
  for (const GroupSummary& g : s.altitudes) add(g);
  return rows;
}

// The table on stdout: fixed-width columns.
std::string Table(const Summaries& s, bool with_z) {
  static constexpr int kWidths[] = {-22, 7, 8, 10, 10, 10, 10, 10, 10, 10};
  const auto line = [](const std::vector<std::string>& cells) {
    std::string text;
    for (std::size_t i = 0; i < cells.size(); ++i) {
      text += Format(i == 0 ? "%*s" : " %*s", kWidths[i], cells[i].c_str());
    }
    return text + "\n";
  };
  std::vector<std::string> header = {"group", "rows", "excluded", "median|e|", "p95|e|", "max|e|", "rel_mae", "mean e"};
  if (with_z) header.insert(header.end(), {"median|z|", "p95|z|"});
  std::string text = line(header);
  for (const auto& row : TableRows(s, with_z)) text += line(row);
  return text;
}

// The same table in Markdown, as docs/accuracy.md shows it ("abs(e)" for "|e|", which would end a
// cell).
std::string MarkdownTable(const Summaries& s, bool with_z) {
  const auto line = [](const std::vector<std::string>& cells) {
    std::string text = "|";
    for (const std::string& cell : cells) text += " " + cell + " |";
    return text + "\n";
  };
  std::vector<std::string> header = {"group", "rows", "excluded", "median abs(e)", "p95 abs(e)", "max abs(e)",
                                     "rel_mae", "mean e"};
  if (with_z) header.insert(header.end(), {"median abs(z)", "p95 abs(z)"});
  std::string text = line(header) + "|---|";
  for (std::size_t i = 1; i < header.size(); ++i) text += "---:|";
  text += "\n";
  for (const auto& row : TableRows(s, with_z)) text += line(row);
  return text;
}

nlohmann::ordered_json SummaryJson(const GroupSummary& g, bool with_z) {
  const auto value = [](double x) -> nlohmann::ordered_json {
    if (std::isfinite(x)) return x;
    return nullptr;
  };
  nlohmann::ordered_json j;
  j["rows"] = g.errors.count;
  j["excluded"] = g.excluded;
  j[std::string(metric_names::kMedianAbs)] = value(g.errors.median_abs);
  j[std::string(metric_names::kP95Abs)] = value(g.errors.p95_abs);
  j[std::string(metric_names::kMaxAbs)] = value(g.errors.max_abs);
  j[std::string(metric_names::kRelMae)] = value(g.errors.rel_mae);
  j[std::string(metric_names::kMean)] = value(g.errors.mean);
  if (with_z) {
    nlohmann::ordered_json z;
    z["rows"] = g.z.count;
    z[std::string(metric_names::kMedianAbs)] = value(g.z.median_abs);
    z[std::string(metric_names::kP95Abs)] = value(g.z.p95_abs);
    z[std::string(metric_names::kMaxAbs)] = value(g.z.max_abs);
    z[std::string(metric_names::kMean)] = value(g.z.mean);
    j[std::string(metric_names::kErrorInStandardErrors)] = z;
  }
  return j;
}

void WriteText(const std::string& path, const std::string& text) {
  WriteFileAtomically(path, [&](const std::filesystem::path& temporary) {
    std::ofstream out(temporary, std::ios::binary);
    out.write(text.data(), static_cast<std::streamsize>(text.size()));
    out.close();
    if (!out) throw Error("write failed");
  });
}

std::string Csv(const std::vector<SamplePoint>& points, const std::vector<Row>& rows,
                const std::vector<double>& wavelengths_nm) {
  const std::size_t channels = wavelengths_nm.size();
  std::string csv =
      "altitude_m,sun_zenith_deg,view_zenith_deg,azimuth_deg,wavelength_nm,radiance,stderr,reference_radiance,"
      "reference_stderr,relative_error,error_in_stderr,included\n";
  for (std::size_t p = 0; p < points.size(); ++p) {
    const SamplePoint& point = points[p];
    const std::string inputs = Format("%.10g,%.10g,%.10g,%.10g,", point.altitude_m, point.sun_zenith_deg,
                                      point.view_zenith_deg, point.azimuth_deg);
    for (std::size_t c = 0; c < channels; ++c) {
      const Row& row = rows[p * channels + c];
      csv += inputs;
      csv += Format("%.10g,%.9e,%.9e,%.9e,%.9e,%.9e,%.6g,%d\n", wavelengths_nm[c], row.radiance, row.standard_error,
                    row.reference, row.reference_standard_error, row.relative_error, row.z, row.included ? 1 : 0);
    }
  }
  return csv;
}

// ---------------------------------------------------------------------------------------------
// The error image: one fisheye per channel, a diverging colour bar and labels in a 5x7 font.

// Columns of 5x7 glyphs (bit 0 the top row), after the classic public-domain LCD font.
struct Glyph {
  char c;
  unsigned char columns[5];
};
constexpr Glyph kFont[] = {
    {' ', {0x00, 0x00, 0x00, 0x00, 0x00}}, {'%', {0x23, 0x13, 0x08, 0x64, 0x62}},
    {'(', {0x00, 0x1C, 0x22, 0x41, 0x00}}, {')', {0x00, 0x41, 0x22, 0x1C, 0x00}},
    {'+', {0x08, 0x08, 0x3E, 0x08, 0x08}}, {',', {0x00, 0x50, 0x30, 0x00, 0x00}},
    {'-', {0x08, 0x08, 0x08, 0x08, 0x08}}, {'.', {0x00, 0x60, 0x60, 0x00, 0x00}},
    {'/', {0x20, 0x10, 0x08, 0x04, 0x02}}, {'0', {0x3E, 0x51, 0x49, 0x45, 0x3E}},
    {'1', {0x00, 0x42, 0x7F, 0x40, 0x00}}, {'2', {0x42, 0x61, 0x51, 0x49, 0x46}},
    {'3', {0x21, 0x41, 0x45, 0x4B, 0x31}}, {'4', {0x18, 0x14, 0x12, 0x7F, 0x10}},
    {'5', {0x27, 0x45, 0x45, 0x45, 0x39}}, {'6', {0x3C, 0x4A, 0x49, 0x49, 0x30}},
    {'7', {0x01, 0x71, 0x09, 0x05, 0x03}}, {'8', {0x36, 0x49, 0x49, 0x49, 0x36}},
    {'9', {0x06, 0x49, 0x49, 0x29, 0x1E}}, {':', {0x00, 0x36, 0x36, 0x00, 0x00}}, {';', {0x00, 0x56, 0x36, 0x00, 0x00}},
    {'=', {0x14, 0x14, 0x14, 0x14, 0x14}}, {'A', {0x7E, 0x11, 0x11, 0x11, 0x7E}},
    {'B', {0x7F, 0x49, 0x49, 0x49, 0x36}}, {'C', {0x3E, 0x41, 0x41, 0x41, 0x22}},
    {'D', {0x7F, 0x41, 0x41, 0x22, 0x1C}}, {'E', {0x7F, 0x49, 0x49, 0x49, 0x41}},
    {'F', {0x7F, 0x09, 0x09, 0x09, 0x01}}, {'G', {0x3E, 0x41, 0x49, 0x49, 0x7A}},
    {'H', {0x7F, 0x08, 0x08, 0x08, 0x7F}}, {'I', {0x00, 0x41, 0x7F, 0x41, 0x00}},
    {'J', {0x20, 0x40, 0x41, 0x3F, 0x01}}, {'K', {0x7F, 0x08, 0x14, 0x22, 0x41}},
    {'L', {0x7F, 0x40, 0x40, 0x40, 0x40}}, {'M', {0x7F, 0x02, 0x0C, 0x02, 0x7F}},
    {'N', {0x7F, 0x04, 0x08, 0x10, 0x7F}}, {'O', {0x3E, 0x41, 0x41, 0x41, 0x3E}},
    {'P', {0x7F, 0x09, 0x09, 0x09, 0x06}}, {'Q', {0x3E, 0x41, 0x51, 0x21, 0x5E}},
    {'R', {0x7F, 0x09, 0x19, 0x29, 0x46}}, {'S', {0x46, 0x49, 0x49, 0x49, 0x31}},
    {'T', {0x01, 0x01, 0x7F, 0x01, 0x01}}, {'U', {0x3F, 0x40, 0x40, 0x40, 0x3F}},
    {'V', {0x1F, 0x20, 0x40, 0x20, 0x1F}}, {'W', {0x3F, 0x40, 0x38, 0x40, 0x3F}},
    {'X', {0x63, 0x14, 0x08, 0x14, 0x63}}, {'Y', {0x07, 0x08, 0x70, 0x08, 0x07}},
    {'Z', {0x61, 0x51, 0x49, 0x45, 0x43}}, {'_', {0x40, 0x40, 0x40, 0x40, 0x40}},
};

const Glyph* FindGlyph(char c) {
  if (c >= 'a' && c <= 'z') c = static_cast<char>(c - 'a' + 'A');
  for (const Glyph& glyph : kFont) {
    if (glyph.c == c) return &glyph;
  }
  return nullptr;  // drawn as a blank
}

constexpr int kGlyphAdvance = 6;  // 5 columns and one blank, times the scale
constexpr int kGlyphHeight = 7;

int TextWidth(const std::string& text, int scale) { return static_cast<int>(text.size()) * kGlyphAdvance * scale; }

void SetPixel(Image& image, int x, int y, const glm::vec3& colour) {
  if (x < 0 || y < 0 || x >= image.width || y >= image.height) return;
  for (int c = 0; c < 3; ++c) image.at(x, y, c) = colour[c];
}

// Draws `text` with its top-left corner at (x, y).
void DrawText(Image& image, int x, int y, const std::string& text, int scale, const glm::vec3& colour) {
  for (std::size_t i = 0; i < text.size(); ++i) {
    const Glyph* glyph = FindGlyph(text[i]);
    if (glyph == nullptr) continue;
    const int left = x + static_cast<int>(i) * kGlyphAdvance * scale;
    for (int column = 0; column < 5; ++column) {
      for (int row = 0; row < kGlyphHeight; ++row) {
        if ((glyph->columns[column] >> row & 1) == 0) continue;
        for (int dy = 0; dy < scale; ++dy) {
          for (int dx = 0; dx < scale; ++dx) SetPixel(image, left + column * scale + dx, y + row * scale + dy, colour);
        }
      }
    }
  }
}

void DrawTextCentred(Image& image, int centre_x, int y, const std::string& text, int scale, const glm::vec3& colour) {
  DrawText(image, centre_x - TextWidth(text, scale) / 2, y, text, scale, colour);
}

void FillRect(Image& image, int x0, int y0, int x1, int y1, const glm::vec3& colour) {
  for (int y = y0; y < y1; ++y) {
    for (int x = x0; x < x1; ++x) SetPixel(image, x, y, colour);
  }
}

// Diverging colour map for t in [-1, 1]: blue (negative, M too dark) through white to red
// (positive, M too bright); ColorBrewer RdBu, 11 classes, interpolated linearly in sRGB.
glm::vec3 Diverging(double t) {
  static const glm::vec3 kStops[] = {
      {0x05, 0x30, 0x61}, {0x21, 0x66, 0xac}, {0x43, 0x93, 0xc3}, {0x92, 0xc5, 0xde},
      {0xd1, 0xe5, 0xf0}, {0xf7, 0xf7, 0xf7}, {0xfd, 0xdb, 0xc7}, {0xf4, 0xa5, 0x82},
      {0xd6, 0x60, 0x4d}, {0xb2, 0x18, 0x2b}, {0x67, 0x00, 0x1f},
  };
  const double u = (std::clamp(t, -1.0, 1.0) + 1.0) * 5.0;  // [0, 10]
  const int i = std::min(static_cast<int>(u), 9);
  const float f = static_cast<float>(u - i);
  return ((1.0f - f) * kStops[i] + f * kStops[i + 1]) / 255.0f;
}

// The fisheye mapping of atmo's camera (shared/camera.glsl, docs/cli.md): equidistant, zenith at
// the centre, horizon on the circle, north up, east left (seen from below). Pixel centres.
bool FisheyeDirection(int x, int y, int size, glm::dvec3& direction) {
  const double radius = 0.5 * size;
  const double dx = (x + 0.5 - 0.5 * size) / radius;
  const double dy = (0.5 * size - (y + 0.5)) / radius;
  const double rho = std::sqrt(dx * dx + dy * dy);
  if (rho > 1.0) return false;
  direction = DirectionFromZenithAzimuth(rho * 0.5 * std::numbers::pi, std::atan2(-dx, dy));
  return true;
}

// Inverse of FisheyeDirection for a direction above the horizontal: pixel coordinates.
glm::dvec2 FisheyePixel(const glm::dvec3& direction, int size) {
  const double zenith = std::acos(std::clamp(direction.z, -1.0, 1.0));
  const double azimuth = std::atan2(direction.x, direction.y);
  const double rho = zenith / (0.5 * std::numbers::pi);
  const double radius = 0.5 * size;
  return {0.5 * size - rho * std::sin(azimuth) * radius, 0.5 * size - rho * std::cos(azimuth) * radius};
}

Image ErrorImage(const Model& model, const Model& reference, const CompareCommand& command, double floor,
                 const std::string& title) {
  const std::size_t channels = model.channel_count();
  const int size = command.image_size;
  const double range = command.image_range_percent / 100.0;
  // The sun in the south (compass azimuth 180: the bottom of the fisheye), as `atmo render`.
  const glm::dvec3 sun = DirectionFromZenithAzimuth(glm::radians(command.image_sun_zenith_deg), std::numbers::pi);
  const std::unique_ptr<SkyView> view = model.View(command.image_altitude_m, sun);
  const std::unique_ptr<SkyView> reference_view = reference.View(command.image_altitude_m, sun);

  // Radiance of both models for every pixel of the disc (NaN outside).
  const std::size_t pixel_count = static_cast<std::size_t>(size) * size;
  std::vector<double> test(pixel_count * channels, kNaN), ref(pixel_count * channels, kNaN);
  oneapi::tbb::parallel_for(0, size, [&](int y) {
    std::vector<double> l(channels), r(channels);
    for (int x = 0; x < size; ++x) {
      glm::dvec3 direction;
      if (!FisheyeDirection(x, y, size, direction)) continue;
      view->Radiance(direction, l);
      reference_view->Radiance(direction, r);
      const std::size_t i = (static_cast<std::size_t>(y) * size + x) * channels;
      std::copy(l.begin(), l.end(), test.begin() + i);
      std::copy(r.begin(), r.end(), ref.begin() + i);
    }
  });
  std::vector<double> brightest(channels, 0.0);
  for (std::size_t i = 0; i < pixel_count; ++i) {
    for (std::size_t c = 0; c < channels; ++c) {
      if (ref[i * channels + c] > brightest[c]) brightest[c] = ref[i * channels + c];
    }
  }

  // Layout: title, the discs side by side with their wavelength, the colour bar with ticks.
  const int margin = 24;
  const int width = margin + static_cast<int>(channels) * (size + margin);
  const int text_scale = width >= 640 ? 2 : 1;
  const int line = (kGlyphHeight + 4) * text_scale;
  const int discs_top = margin + 2 * line + line;  // two title lines, then room for "N"
  const int bar_top = discs_top + size + 2 * line;
  const int bar_height = 16;
  const int height = bar_top + bar_height + 8 + line + margin / 2 + line;
  Image image(width, height, 3);
  const glm::vec3 background(0.82f), black(0.0f), grey(0.55f);
  FillRect(image, 0, 0, width, height, background);

  DrawText(image, margin, margin / 2, title, text_scale, black);
  DrawText(image, margin, margin / 2 + line,
           Format("ALTITUDE %.10g M, SUN ZENITH %.10g (SOUTH, AT THE BOTTOM)", command.image_altitude_m,
                  command.image_sun_zenith_deg),
           text_scale, black);

  const glm::dvec2 sun_pixel = FisheyePixel(sun, size);
  for (std::size_t c = 0; c < channels; ++c) {
    const int left = margin + static_cast<int>(c) * (size + margin);
    for (int y = 0; y < size; ++y) {
      for (int x = 0; x < size; ++x) {
        const std::size_t i = (static_cast<std::size_t>(y) * size + x) * channels + c;
        if (std::isnan(ref[i]) && std::isnan(test[i])) continue;  // outside the circle
        const bool below_floor = !(ref[i] > 0.0 && ref[i] > floor * brightest[c]);
        SetPixel(image, left + x, discs_top + y,
                 below_floor ? grey : Diverging(RelativeError(test[i], ref[i]) / range));
      }
    }
    // The horizon circle, and a ring around the sun when it is above the horizon.
    for (int k = 0; k < 8 * size; ++k) {
      const double a = 2.0 * std::numbers::pi * k / (8 * size);
      SetPixel(image, left + static_cast<int>(std::lround(0.5 * size + 0.5 * size * std::cos(a) - 0.5)),
               discs_top + static_cast<int>(std::lround(0.5 * size + 0.5 * size * std::sin(a) - 0.5)), black);
      if (command.image_sun_zenith_deg < 90.0) {
        const double ring = std::max(3.0, size / 40.0);
        SetPixel(image, left + static_cast<int>(std::lround(sun_pixel.x + ring * std::cos(a) - 0.5)),
                 discs_top + static_cast<int>(std::lround(sun_pixel.y + ring * std::sin(a) - 0.5)), black);
      }
    }
    DrawTextCentred(image, left + size / 2, discs_top - line, "N", text_scale, black);
    DrawText(image, left - TextWidth("E", text_scale) - 2, discs_top + size / 2 - line / 2, "E", text_scale, black);
    DrawTextCentred(image, left + size / 2, discs_top + size + line / 2,
                    Format("%.10g NM", model.parameters().wavelengths_nm[c]), text_scale, black);
  }

  // The colour bar: -range on the left, +range on the right, five ticks; inset so that the end
  // labels fit.
  const int label_half_width = TextWidth(Format("%+.3g%%", command.image_range_percent), text_scale) / 2;
  const int bar_left = margin + label_half_width;
  const int bar_right = width - margin - label_half_width;
  for (int x = bar_left; x < bar_right; ++x) {
    const double t = 2.0 * (x + 0.5 - bar_left) / (bar_right - bar_left) - 1.0;
    FillRect(image, x, bar_top, x + 1, bar_top + bar_height, Diverging(t));
  }
  for (int k = 0; k <= 4; ++k) {
    const double t = -1.0 + 0.5 * k;
    const int x = std::min(bar_right - 1, bar_left + static_cast<int>(std::lround((t + 1.0) / 2.0 * (bar_right - bar_left))));
    FillRect(image, x, bar_top, x + 1, bar_top + bar_height + 6, black);
    const double percent = t * command.image_range_percent;
    const std::string label = percent == 0.0 ? "0" : Format("%+.3g%%", percent);
    DrawTextCentred(image, x, bar_top + bar_height + 8, label, text_scale, black);
  }
  const int legend_y = bar_top + bar_height + 8 + line;
  DrawText(image, margin, legend_y, "RELATIVE ERROR (M - R)/R, CLAMPED; GREY: R BELOW FLOOR", text_scale, black);
  return image;
}

}  // namespace

int RunCompare(const CommonOptions& common, const CompareCommand& command) {
  CheckBackend(common);
  CheckOutputsApart(common,
                    {{"--grid", IsNamedGrid(command.grid) ? std::string() : command.grid},
                     {"--against-samples", command.against_samples == "-" ? std::string() : command.against_samples}},
                    {{"--csv", command.csv_path},
                     {"--json", command.json_path},
                     {"--markdown", command.markdown_path},
                     {"--image", command.image_path}});
  if (!(command.floor >= 0.0 && command.floor <= 1.0)) {
    throw Error(Format("--floor %g is outside [0, 1]", command.floor));
  }
  const AtmosphereParameters parameters = LoadParameters(common);
  const bool from_samples = !command.against_samples.empty();
  if (from_samples && !command.image_path.empty()) {
    throw Error("--image needs a reference model, not --against-samples");
  }
  SampleTable samples;
  if (from_samples) samples = ReadSamples(command.against_samples, parameters.wavelengths_nm);
  const std::vector<SamplePoint> points = from_samples ? samples.points : GridFor(command.grid, parameters);
  for (const std::string& path : {command.csv_path, command.json_path, command.markdown_path, command.image_path}) {
    if (!path.empty()) CheckOutputWritable(path);
  }
  CheckExtension("--csv", command.csv_path, ".csv");
  CheckExtension("--json", command.json_path, ".json");
  CheckExtension("--markdown", command.markdown_path, ".md");
  CheckExtension("--image", command.image_path, ".png");

  const ModelOptions options = EffectiveOptions(common.options, common);
  const ModelOptions reference_options = EffectiveOptions(command.against_options, common);
  const std::string model_text = Describe(common.model, options);
  const std::string reference_name = from_samples ? "samples" : command.against;
  const std::string reference_text =
      from_samples ? "the samples of " + command.against_samples : Describe(command.against, reference_options);
  const std::string preset = common.config.empty() ? common.preset : common.config;
  const std::string hash = ParameterHashHex(parameters);
  const std::string& grid = from_samples ? command.against_samples : command.grid;
  const std::vector<double>& wavelengths_nm = parameters.wavelengths_nm;
  // The header comes before the work (a Monte Carlo reference takes minutes), the table after it.
  std::string header = Format("atmo compare: %s against %s; parameters %s (hash %s); grid %s\n", model_text.c_str(),
                              reference_text.c_str(), preset.c_str(), hash.c_str(), grid.c_str());
  header += Format("%zu configurations x %zu channels = %zu rows; e = (M - R)/R, M: %s, R: %s\n", points.size(),
                   wavelengths_nm.size(), points.size() * wavelengths_nm.size(), common.model.c_str(),
                   reference_name.c_str());
  if (std::fwrite(header.data(), 1, header.size(), stdout) != header.size() || std::fflush(stdout) != 0) {
    throw Error("cannot write to standard output");
  }
  const auto start = std::chrono::steady_clock::now();
  const auto seconds_since = [](std::chrono::steady_clock::time_point t) {
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - t).count();
  };
  const std::unique_ptr<Model> model = CreateModel(common.model, parameters, options);
  const double model_precompute_s = seconds_since(start);
  const auto reference_start = std::chrono::steady_clock::now();
  const std::unique_ptr<Model> reference =
      from_samples ? nullptr : CreateModel(command.against, parameters, reference_options);
  const double reference_precompute_s = seconds_since(reference_start);
  if (reference && reference->channel_count() != model->channel_count()) {
    throw Error("the models have different channel counts");
  }

  const auto evaluate_start = std::chrono::steady_clock::now();
  ProgressBar bar("compare: configurations");
  const std::vector<Row> rows =
      Evaluate(*model, reference.get(), from_samples ? &samples : nullptr, points, command.floor,
               [&bar](std::size_t done, std::size_t total) { bar.Update(static_cast<double>(done), static_cast<double>(total)); });
  bar.Finish();
  const double evaluate_s = seconds_since(evaluate_start);
  const Summaries summaries = SummarizeAll(points, rows, wavelengths_nm);
  const bool with_z = std::any_of(rows.begin(), rows.end(), [](const Row& row) { return !std::isnan(row.z); });

  std::string report = Format("excluded from the statistics: rows with R <= %g x the largest R of their sky (same altitude, "
                   "sun zenith, channel)\n",
                   command.floor);
  report += "sun zenith bands (deg): sun up < 90 <= twilight <= 100 < night\n";
  if (with_z) report += "z = (M - R)/sqrt(se_M^2 + se_R^2), the error in standard errors\n";
  report += '\n';
  report += Table(summaries, with_z);
  const std::size_t worst = WorstRow(rows);
  std::string largest;
  if (worst < rows.size()) {
    const std::size_t channels = wavelengths_nm.size();
    const SamplePoint& p = points[worst / channels];
    const Row& row = rows[worst];
    largest = Format("largest |e|: %s at altitude %.10g m, sun zenith %.10g, view zenith %.10g, azimuth %.10g, "
                     "%.10g nm (M = %.4e, R = %.4e)\n",
                     Percent(row.relative_error).c_str(), p.altitude_m, p.sun_zenith_deg, p.view_zenith_deg,
                     p.azimuth_deg, wavelengths_nm[worst % channels], row.radiance, row.reference);
    report += "\n" + largest;
  }

  if (!command.csv_path.empty()) WriteText(command.csv_path, Csv(points, rows, wavelengths_nm));
  if (!command.markdown_path.empty()) {
    std::string markdown = MarkdownTable(summaries, with_z);
    if (!largest.empty()) markdown += "\nL" + largest.substr(1);
    WriteText(command.markdown_path, markdown);
  }
  if (!command.json_path.empty()) {
    nlohmann::ordered_json j;
    j["atmo_version"] = ATMO_VERSION;
    j["command"] = "compare";
    j["model"] = {{"name", common.model}, {"options", options}};
    if (from_samples) {
      j["reference"] = {{"samples", command.against_samples}};
    } else {
      j["reference"] = {{"name", command.against}, {"options", reference_options}};
    }
    j["preset"] = common.config.empty() ? nlohmann::ordered_json(common.preset) : nlohmann::ordered_json(nullptr);
    j["config"] = common.config.empty() ? nlohmann::ordered_json(nullptr) : nlohmann::ordered_json(common.config);
    j["parameter_hash"] = hash;
    j["grid"] = grid;
    j["configurations"] = points.size();
    j["wavelengths_nm"] = wavelengths_nm;
    j["rows"] = rows.size();
    j["relative_error"] = "(M - R) / R per configuration and channel; M the model, R the reference";
    j["error_in_stderr"] = "(M - R) / sqrt(se_M^2 + se_R^2), where a standard error is reported";
    j["percentile"] = "linear interpolation between closest ranks (Hyndman-Fan type 7)";
    j["floor"] = {{"relative", command.floor},
                  {"rule", "a row is excluded when R <= relative x the largest R of its sky (same altitude, "
                           "sun zenith, channel) or R <= 0"}};
    j["overall"] = SummaryJson(summaries.overall, with_z);
    nlohmann::ordered_json channel_list = nlohmann::ordered_json::array();
    for (std::size_t c = 0; c < summaries.channels.size(); ++c) {
      nlohmann::ordered_json entry = {{"wavelength_nm", wavelengths_nm[c]}};
      entry.update(SummaryJson(summaries.channels[c], with_z));
      channel_list.push_back(entry);
    }
    j["channels"] = channel_list;
    nlohmann::ordered_json bands = nlohmann::ordered_json::array();
    for (std::size_t b = 0; b < summaries.bands.size(); ++b) {
      const SunBand& band = kSunBands[summaries.band_indices[b]];
      nlohmann::ordered_json entry = {{"band", band.key},
                                      {"definition", band.definition},
                                      {"sun_zenith_min_deg", band.min_deg},
                                      {"sun_zenith_max_deg", band.max_deg}};
      entry.update(SummaryJson(summaries.bands[b], with_z));
      bands.push_back(entry);
    }
    j["sun_zenith_bands"] = bands;
    nlohmann::ordered_json altitudes = nlohmann::ordered_json::array();
    for (std::size_t a = 0; a < summaries.altitudes.size(); ++a) {
      nlohmann::ordered_json entry = {{"altitude_m", summaries.altitude_values[a]}};
      entry.update(SummaryJson(summaries.altitudes[a], with_z));
      altitudes.push_back(entry);
    }
    j["altitudes"] = altitudes;
    if (worst < rows.size()) {
      const std::size_t channels = wavelengths_nm.size();
      const SamplePoint& p = points[worst / channels];
      j["largest_error"] = {{"altitude_m", p.altitude_m},         {"sun_zenith_deg", p.sun_zenith_deg},
                            {"view_zenith_deg", p.view_zenith_deg}, {"azimuth_deg", p.azimuth_deg},
                            {"wavelength_nm", wavelengths_nm[worst % channels]},
                            {"radiance", rows[worst].radiance},     {"reference_radiance", rows[worst].reference},
                            {"relative_error", rows[worst].relative_error}};
    }
    j["timing_s"] = {{"model_precompute", model_precompute_s},
                     {"reference_precompute", reference_precompute_s},
                     {"evaluate", evaluate_s}};
    WriteText(command.json_path, j.dump(2) + "\n");
  }
  if (!command.image_path.empty()) {
    const Image image =
        ErrorImage(*model, *reference, command, command.floor, model_text + " VS " + reference_text);
    // The chart's values are display values already: written as they are (no curve, no dither).
    ToneMapping chart = SeedToneMapping(ToneMapper::kNone, /*exposure=*/1.0, /*gamma=*/1.0);
    chart.transfer = DisplayTransfer::kIdentity;
    WritePng(command.image_path, image, chart);
  }

  if (std::fwrite(report.data(), 1, report.size(), stdout) != report.size() || std::fflush(stdout) != 0) {
    throw Error("cannot write to standard output");
  }
  return 0;
}

}  // namespace atmo::cli
