// The files of an annual run (include/atmo/annual.h): run.json, the parts, and the merged
// sky.mtx, hours.csv and irradiance.csv (docs/daylighting.md).
#include <algorithm>
#include <cstdio>
#include <fstream>
#include <map>
#include <numbers>
#include <set>
#include <sstream>
#include <string>

#include <nlohmann/json.hpp>

#include "atmo/annual.h"
#include "atmo/colour.h"
#include "atmo/error.h"
#include "atmo/image.h"
#include "atmo/render.h"
#include "atmo/spectrum.h"
#include "printable.h"

namespace atmo {

namespace {

namespace fs = std::filesystem;

std::string Fnv1aOfFile(const fs::path& path, std::uintmax_t& bytes) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw Error("cannot read " + Printable(path.string()));
  std::uint64_t h = 1469598103934665603ull;
  bytes = 0;
  char buffer[1 << 16];
  while (in) {
    in.read(buffer, sizeof buffer);
    const std::streamsize got = in.gcount();
    for (std::streamsize i = 0; i < got; ++i) {
      h ^= static_cast<unsigned char>(buffer[i]);
      h *= 1099511628211ull;
    }
    bytes += static_cast<std::uintmax_t>(got);
  }
  char text[17];
  std::snprintf(text, sizeof text, "%016llx", static_cast<unsigned long long>(h));
  return text;
}

// What decides the results: a rerun or another shard must match it.
std::string Fingerprint(const AnnualSkies& skies) {
  const AnnualSettings& s = skies.settings();
  nlohmann::ordered_json j;
  std::uintmax_t bytes = 0;
  j["epw_fnv1a"] = Fnv1aOfFile(skies.weather().path, bytes);
  j["epw_bytes"] = bytes;
  j["parameters_hash"] = ParameterHashHex(skies.base());
  j["model"] = s.model;
  j["options"] = s.options;
  j["aerosol_type"] = s.aerosol_type;
  nlohmann::json planes = nlohmann::json::array();
  for (const Plane& p : s.planes) planes.push_back(p.tracks_sun ? nlohmann::json("sun") : nlohmann::json({p.tilt_deg, p.azimuth_deg}));
  j["planes"] = planes;
  j["sky_subdivision"] = s.sky_subdivision;
  j["patch_samples"] = s.patch_samples;
  j["circumsolar_half_angle_deg"] = s.circumsolar_half_angle_deg;
  j["aod_nodes"] = s.aod_nodes;
  j["albedo_nodes"] = s.albedo_nodes;
  j["min_single_scattering_albedo"] = s.min_single_scattering_albedo;
  j["min_sun_elevation_deg"] = s.min_sun_elevation_deg;
  j["sun_in_matrix"] = s.sun_in_matrix;
  j["sky_map_size"] = s.sky_map_size;
  if (s.per_wavelength) j["per_wavelength"] = true;  // absent when off: the runs of before match
  return j.dump(2) + "\n";
}

std::string ReadText(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw Error("cannot read " + Printable(path.string()));
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

std::string G(double v) {
  char b[32];
  std::snprintf(b, sizeof b, "%.9g", v);
  return b;
}

// One hour as part lines: H (the hour), P (each plane), S (each plane per channel, with
// per_wavelength), M (the matrix column).
std::string PartLines(const AnnualSkies& skies, const SpectralConversion& convert, const HourSky& h) {
  std::string out = "H," + std::to_string(h.hour) + "," + std::string(ToString(h.status)) + "," +
                    G(h.julian_day_utc) + "," + G(h.sun_elevation_deg) + "," + G(h.sun_azimuth_deg) + "," +
                    G(h.aod_550) + "," + G(h.single_scattering_albedo_550) + "," + G(h.clear_fraction) + "," +
                    G(h.overcast_lux) + "," + G(h.direct_normal_lux) + "," + G(h.diffuse_horizontal_lux) + "\n";
  for (std::size_t p = 0; p < h.planes.size(); ++p) {
    const IrradianceComponents& e = h.planes[p];
    const std::vector<double> global = e.Global();
    const std::vector<double>* parts[] = {&e.direct, &e.circumsolar, &e.sky_diffuse, &e.ground_reflected, &global};
    out += "P," + std::to_string(h.hour) + "," + std::to_string(p);
    for (const auto* part : parts) out.append(1, ',').append(G(convert.Luminance(*part)));
    for (const auto* part : parts) out.append(1, ',').append(G(convert.Radiance(*part)));
    out += "\n";
    if (skies.settings().per_wavelength) {
      // Channel by channel, the five parts of each (W m^-2 nm^-1).
      out += "S," + std::to_string(h.hour) + "," + std::to_string(p);
      for (std::size_t c = 0; c < skies.channel_count(); ++c) {
        for (const auto* part : parts) out.append(1, ',').append(G(convert.SpectralRadiance(c, (*part)[c])));
      }
      out += "\n";
    }
  }
  if (!h.patch_radiance.empty()) {
    const std::size_t n = skies.channel_count();
    out += "M," + std::to_string(h.hour);
    for (std::size_t r = 0; r < h.patch_radiance.size() / n; ++r) {
      const std::span<const double> radiance(&h.patch_radiance[r * n], n);
      const glm::dvec3 rgb = XyzToRadianceRgbInGamut(kMaxLuminousEfficacy * convert.Xyz(radiance));
      for (int k = 0; k < 3; ++k) out.append(1, ',').append(G(rgb[k]));
    }
    out += "\n";
  }
  return out;
}

// Radiance's function file for the maps: (u, v) in the picture of a direction (Dx, Dy, Dz).
constexpr const char* kSkyCal =
    "{ atmo_sky.cal: where a direction falls in the sky maps of atmo annual (docs/daylighting.md):\n"
    "  angular fisheye pictures, the zenith at the centre, the horizon on the inscribed circle,\n"
    "  north up and east right as seen from above. }\n"
    "sky_r = acos(Dz) / PI;\n"
    "sky_h = sqrt(Dx * Dx + Dy * Dy);\n"
    "sky_u = .5 + if(sky_h - 1e-9, sky_r * Dx / sky_h, 0);\n"
    "sky_v = .5 + if(sky_h - 1e-9, sky_r * Dy / sky_h, 0);\n";

std::string HourName(std::size_t hour) {
  char name[32];
  std::snprintf(name, sizeof name, "sky_%04zu", hour);
  return name;
}

// The scene of one hour, as gendaylit writes a sky: the sun a 0.533-degree `light` source, the sky
// a `glow` through the map, the ground a uniform `glow`.
std::string HourScene(const AnnualSkies& skies, const SpectralConversion& convert, const HourSky& h) {
  const std::size_t n = skies.channel_count();
  const WeatherHour& w = skies.weather().hours[h.hour];
  const auto rgb_of = [&](std::span<const double> relative) {
    return XyzToRadianceRgbInGamut(kMaxLuminousEfficacy * convert.Xyz(relative));
  };
  std::string out = "# atmo annual: " + Printable(skies.weather().path.filename().string()) + ", hour " +
                    std::to_string(h.hour) + " (" + std::to_string(w.year) + "-" + std::to_string(w.month) + "-" +
                    std::to_string(w.day) + ", the hour ending " + std::to_string(w.hour) +
                    ":00 local standard time), status " + std::string(ToString(h.status)) + "\n# sun elevation " +
                    G(h.sun_elevation_deg) + ", azimuth " + G(h.sun_azimuth_deg) + " (compass); aod_550 " +
                    G(h.aod_550) + ", omega_550 " + G(h.single_scattering_albedo_550) + "\n# +X east, +Y north, +Z up\n";
  const std::vector<double>& direct = h.planes.size() > 1 ? h.planes[1].direct : std::vector<double>{};
  const bool sun = !direct.empty() && h.sun_elevation_deg > 0.0;
  if (sun) {
    const double radius = glm::radians(0.533 / 2.0);
    const double omega = 2.0 * std::numbers::pi * (1.0 - std::cos(radius));
    const glm::dvec3 rgb = rgb_of(direct) / omega;
    const glm::dvec3 d = SunDirection(h.sun_elevation_deg, h.sun_azimuth_deg);
    out += "\nvoid light solar\n0\n0\n3 " + G(rgb.x) + " " + G(rgb.y) + " " + G(rgb.z) + "\n\nsolar source sun\n0\n0\n4 " +
           G(d.x) + " " + G(d.y) + " " + G(d.z) + " 0.533\n";
  }
  const glm::dvec3 ground = rgb_of(std::span<const double>(h.patch_radiance.data(), n));
  out += "\nvoid colorpict sky_map\n7 red green blue " + HourName(h.hour) +
         ".hdr atmo_sky.cal sky_u sky_v\n0\n0\n\nsky_map glow sky_glow\n0\n0\n4 1 1 1 0\n\nsky_glow source sky\n0\n0\n"
         "4 0 0 1 180\n\nvoid glow ground_glow\n0\n0\n4 " +
         G(ground.x) + " " + G(ground.y) + " " + G(ground.z) + " 0\n\nground_glow source ground\n0\n0\n4 0 0 -1 180\n";
  return out;
}

struct PartHour {
  std::vector<std::string> h;               // the H fields after the hour
  std::vector<std::vector<std::string>> p;  // per plane, the fields after the plane index
  std::vector<std::vector<std::string>> s;  // per plane, the S fields after the plane index
  std::string m;                            // the M values, comma-separated
};

std::vector<std::string> Split(const std::string& line) {
  const std::vector<std::string_view> fields = SplitCommas(line);
  return {fields.begin(), fields.end()};
}

// Every hour found in the parts of `out_dir`.
std::map<std::size_t, PartHour> ReadParts(const fs::path& out_dir) {
  std::map<std::size_t, PartHour> hours;
  const fs::path folder = out_dir / "parts";
  std::error_code error;
  if (!fs::is_directory(folder, error)) return hours;
  std::vector<fs::path> files;
  for (const fs::directory_entry& entry : fs::directory_iterator(folder)) {
    const std::string name = entry.path().filename().string();
    if (name.rfind("part-", 0) == 0 && entry.path().extension() == ".txt") files.push_back(entry.path());
  }
  std::sort(files.begin(), files.end());
  for (const fs::path& file : files) {
    std::istringstream in(ReadText(file));
    std::string line;
    int number = 0;
    while (std::getline(in, line)) {
      ++number;
      if (line.empty()) continue;
      const std::size_t c1 = line.find(',');
      const std::size_t c2 = line.find(',', c1 + 1);
      if (line.size() < 3 || line[1] != ',' || c2 == std::string::npos) {
        throw Error(Printable(file.string()) + ":" + std::to_string(number) + ": not a part line");
      }
      const std::size_t hour = std::stoul(line.substr(c1 + 1, c2 - c1 - 1));
      const std::string rest = line.substr(c2 + 1);
      PartHour& h = hours[hour];
      if (line[0] == 'H') {
        if (!h.h.empty()) continue;  // the same hour twice (never from atmo itself): the first stays
        h.h = Split(rest);
      } else if (line[0] == 'P' || line[0] == 'S') {
        std::vector<std::string> f = Split(rest);
        const std::size_t plane = std::stoul(f[0]);
        std::vector<std::vector<std::string>>& planes = line[0] == 'P' ? h.p : h.s;
        if (planes.size() <= plane) planes.resize(plane + 1);
        if (planes[plane].empty()) planes[plane].assign(f.begin() + 1, f.end());
      } else if (line[0] == 'M') {
        if (h.m.empty()) h.m = rest;
      } else {
        throw Error(Printable(file.string()) + ":" + std::to_string(number) + ": not a part line");
      }
    }
  }
  for (auto it = hours.begin(); it != hours.end();) it = it->second.h.empty() ? hours.erase(it) : std::next(it);
  return hours;
}

std::vector<std::string> PlaneLabels(const AnnualSettings& s) {
  std::vector<std::string> labels = {"horizontal", "sun"};
  for (const Plane& p : s.planes) labels.push_back(p.tracks_sun ? "sun" : G(p.tilt_deg) + ":" + G(p.azimuth_deg));
  return labels;
}

}  // namespace

AnnualRunReport RunAnnual(AnnualSkies& skies, const AnnualRun& run,
                          const std::function<void(const std::string&)>& progress) {
  if (run.shards < 1 || run.shard < 0 || run.shard >= run.shards) {
    throw Error("--shard I/N needs 0 <= I < N, got " + std::to_string(run.shard) + "/" + std::to_string(run.shards));
  }
  const std::size_t total = skies.weather().hours.size();
  const std::size_t end = std::min(run.end_hour, total);
  if (run.first_hour >= end) {
    throw Error("--hours selects no hour of the file (" + std::to_string(total) + " hours, 0.." + std::to_string(total) + ")");
  }
  std::error_code error;
  fs::create_directories(run.out_dir / "parts", error);
  if (error) throw Error("cannot make the folder " + Printable((run.out_dir / "parts").string()) + ": " + error.message());
  const std::string fingerprint = Fingerprint(skies);
  const fs::path record = run.out_dir / "run.json";
  if (fs::exists(record, error)) {
    if (ReadText(record) != fingerprint) {
      throw Error(Printable(run.out_dir.string()) + " holds a run of other settings, parameters or weather (its run.json): "
                  "give another --out-dir or remove it");
    }
  } else {
    WriteTextFileAtomically(record, fingerprint);
  }

  AnnualRunReport report;
  std::set<std::size_t> done;
  for (const auto& [hour, _] : ReadParts(run.out_dir)) done.insert(hour);
  std::vector<std::size_t> todo;
  for (std::size_t h = run.first_hour; h < end; ++h) {
    if ((h / 24) % static_cast<std::size_t>(run.shards) != static_cast<std::size_t>(run.shard)) continue;
    ++report.selected;
    if (done.count(h)) {
      ++report.already_done;
    } else {
      todo.push_back(h);
    }
  }
  const SpectralConversion convert(skies.base().wavelengths_nm);
  const bool maps = skies.settings().sky_map_size > 0;
  if (maps) {
    fs::create_directories(run.out_dir / "maps", error);
    if (error) throw Error("cannot make the folder " + Printable((run.out_dir / "maps").string()) + ": " + error.message());
    WriteTextFileAtomically(run.out_dir / "maps" / "atmo_sky.cal", kSkyCal);
  }
  const int built_before = skies.models_built();
  std::size_t written = 0;
  skies.Compute(
      todo,
      [&](std::size_t finished) {
        if (progress && (finished % 100 == 0 || finished == todo.size())) {
          progress(std::to_string(finished) + " of " + std::to_string(todo.size()) + " hours");
        }
      },
      [&](std::span<const HourSky> group) {
        std::string text;
        std::size_t first = group.front().hour, last = group.front().hour;
        for (const HourSky& h : group) {
          if (maps && h.sky_map.width > 0) {
            WriteRadianceHdr(run.out_dir / "maps" / (HourName(h.hour) + ".hdr"), h.sky_map);
            WriteTextFileAtomically(run.out_dir / "maps" / (HourName(h.hour) + ".rad"), HourScene(skies, convert, h));
          }
          text += PartLines(skies, convert, h);
          first = std::min(first, h.hour);
          last = std::max(last, h.hour);
        }
        const fs::path part = run.out_dir / "parts" /
                              ("part-" + std::to_string(first) + "-" + std::to_string(last) + "-" +
                               std::to_string(group.size()) + ".txt");
        WriteTextFileAtomically(part, text);
        written += group.size();
      });
  report.computed = written;
  report.models_built = skies.models_built() - built_before;
  report.file_done = done.size() + written;
  report.merged = MergeAnnual(skies, run.out_dir);
  return report;
}

bool MergeAnnual(const AnnualSkies& skies, const fs::path& out_dir) {
  const std::map<std::size_t, PartHour> parts = ReadParts(out_dir);
  const std::vector<WeatherHour>& hours = skies.weather().hours;
  for (std::size_t h = 0; h < hours.size(); ++h) {
    if (!parts.count(h)) return false;
  }
  const std::vector<std::string> labels = PlaneLabels(skies.settings());
  std::string hours_csv =
      "hour,month,day,hour_of_day,julian_day_utc,status,sun_elevation_deg,sun_azimuth_deg,aod_550,omega_550,"
      "clear_fraction,overcast_diffuse_lux,measured_direct_normal_lux,measured_diffuse_horizontal_lux,"
      "direct_normal_lux,diffuse_horizontal_lux\n";
  std::string irradiance_csv =
      "hour,month,day,hour_of_day,plane,direct_lux,circumsolar_lux,sky_diffuse_lux,ground_reflected_lux,global_lux,"
      "direct_w_m2,circumsolar_w_m2,sky_diffuse_w_m2,ground_reflected_w_m2,global_w_m2\n";
  const bool spectral = skies.settings().per_wavelength;
  const std::vector<double>& wavelengths = skies.base().wavelengths_nm;
  std::string spectral_csv =
      "hour,month,day,hour_of_day,plane,wavelength_nm,direct_w_m2_nm,circumsolar_w_m2_nm,sky_diffuse_w_m2_nm,"
      "ground_reflected_w_m2_nm,global_w_m2_nm\n";
  for (std::size_t h = 0; h < hours.size(); ++h) {
    const PartHour& part = parts.at(h);
    const WeatherHour& w = hours[h];
    const std::string when =
        std::to_string(h) + "," + std::to_string(w.month) + "," + std::to_string(w.day) + "," + std::to_string(w.hour);
    if (part.h.size() != 10) throw Error("the parts of hour " + std::to_string(h) + " are malformed");
    hours_csv += when + "," + part.h[1] + "," + part.h[0];
    for (std::size_t k = 2; k < 8; ++k) hours_csv += "," + part.h[k];
    hours_csv += "," + G(w.direct_normal_lux) + "," + G(w.diffuse_horizontal_lux) + "," + part.h[8] + "," + part.h[9] + "\n";
    for (std::size_t p = 0; p < part.p.size() && p < labels.size(); ++p) {
      irradiance_csv += when + "," + labels[p];
      for (const std::string& v : part.p[p]) irradiance_csv += "," + v;
      irradiance_csv += "\n";
      if (!spectral) continue;
      constexpr std::size_t kParts = 5;
      if (p >= part.s.size() || part.s[p].size() != kParts * wavelengths.size()) {
        throw Error("the per-wavelength parts of hour " + std::to_string(h) + " are malformed");
      }
      for (std::size_t c = 0; c < wavelengths.size(); ++c) {
        spectral_csv += when + "," + labels[p] + "," + G(wavelengths[c]);
        for (std::size_t k = 0; k < kParts; ++k) spectral_csv += "," + part.s[p][kParts * c + k];
        spectral_csv += "\n";
      }
    }
  }
  // The matrix: row r (ground, then patches), column c (hour): "R G B" per line, rows apart by a
  // blank line, as gendaymtx writes its ASCII matrices; written as it is formatted (a 2305-patch
  // year is about 0.6 GB of text).
  const std::size_t rows = skies.patches().count() + 1;
  std::vector<std::vector<float>> columns(hours.size());
  for (std::size_t h = 0; h < hours.size(); ++h) {
    const std::string& m = parts.at(h).m;
    if (m.empty()) continue;
    const std::vector<std::string> values = Split(m);
    if (values.size() != 3 * rows) throw Error("the matrix column of hour " + std::to_string(h) + " is malformed");
    columns[h].reserve(values.size());
    for (const std::string& v : values) columns[h].push_back(std::stof(v));
  }
  const std::string header = "#?RADIANCE\natmo annual: sky matrix of " +
                             Printable(skies.weather().path.filename().string()) + " (ground, then Reinhart MF " +
                             std::to_string(skies.settings().sky_subdivision) +
                             " patches; Radiance RGB radiance, W sr^-1 m^-2)\nNROWS=" + std::to_string(rows) +
                             "\nNCOLS=" + std::to_string(hours.size()) + "\nNCOMP=3\nFORMAT=ascii\n\n";
  WriteTextFileAtomically(out_dir / "hours.csv", hours_csv);
  WriteTextFileAtomically(out_dir / "irradiance.csv", irradiance_csv);
  if (spectral) WriteTextFileAtomically(out_dir / "irradiance_spectral.csv", spectral_csv);
  WriteFileAtomically(out_dir / "sky.mtx", [&](const fs::path& temporary) {
    std::ofstream out(temporary, std::ios::binary);
    out << header;
    char line[64];
    for (std::size_t r = 0; r < rows; ++r) {
      for (std::size_t h = 0; h < hours.size(); ++h) {
        if (columns[h].empty()) {
          out << "0 0 0\n";
        } else {
          std::snprintf(line, sizeof line, "%.6g %.6g %.6g\n", columns[h][3 * r], columns[h][3 * r + 1], columns[h][3 * r + 2]);
          out << line;
        }
      }
      out << "\n";
    }
    out.close();
    if (!out) throw Error("write failed");
  });
  return true;
}

}  // namespace atmo
