// Atmosphere parameters as JSON: the keys of docs/parameters.md.
//
// ToJson writes every key in a fixed order, so its output is canonical (ParameterHash hashes it)
// and reads back to the same parameters. FromJson starts from a preset and overrides only what the
// document holds; nested objects merge key by key, and a per-channel key may be a single number
// that applies to every channel.
#include <cerrno>
#include <cstring>
#include <fstream>
#include <initializer_list>
#include <sstream>
#include <string>

#include <nlohmann/json.hpp>

#include "atmo/aerosol.h"
#include "atmo/error.h"
#include "atmo/image.h"
#include "atmo/parameters.h"
#include "printable.h"

namespace atmo {
namespace {

using Json = nlohmann::json;
using OrderedJson = nlohmann::ordered_json;

// The name a config's "preset" key may hold for parameters that match no preset: FromJson then
// starts from `earth`, which the keys of the document override.
constexpr std::string_view kCustomName = "custom";
constexpr std::string_view kDefaultPreset = "earth";

constexpr PhaseFunction kPhaseFunctions[] = {
    PhaseFunction::kIsotropic, PhaseFunction::kRayleigh, PhaseFunction::kModifiedRayleigh,
    PhaseFunction::kCornetteShanks, PhaseFunction::kHenyeyGreenstein, PhaseFunction::kTabulated};
constexpr Geometry kGeometries[] = {Geometry::kSpherical, Geometry::kHalfSpace};

// ---------------------------------------------------------------------------------------------
// Writing.

OrderedJson LayerToJson(const DensityLayer& layer) {
  OrderedJson j;
  j["width_m"] = layer.width_m;
  j["exp_term"] = layer.exp_term;
  j["exp_scale_per_m"] = layer.exp_scale_per_m;
  j["linear_term_per_m"] = layer.linear_term_per_m;
  j["constant_term"] = layer.constant_term;
  return j;
}

OrderedJson MediumToJson(const Medium& medium) {
  OrderedJson j;
  j["scattering_per_m"] = medium.scattering_per_m;
  j["absorption_per_m"] = medium.absorption_per_m;
  j["phase_function"] = std::string(ToString(medium.phase));
  j["phase_g"] = medium.phase_g;
  if (medium.phase == PhaseFunction::kTabulated) {
    OrderedJson table = OrderedJson::array();
    for (const PhaseSample& sample : medium.phase_table) table.push_back({sample.angle_deg, sample.value});
    j["phase_table"] = std::move(table);
  }
  if (medium.density.tabulated()) {
    OrderedJson table = OrderedJson::array();
    for (const DensityKnot& knot : medium.density.table) table.push_back({knot.altitude_m, knot.density});
    j["density"]["table"] = std::move(table);
  } else {
    j["density"]["lower"] = LayerToJson(medium.density.lower);
    j["density"]["upper"] = LayerToJson(medium.density.upper);
  }
  return j;
}

// ---------------------------------------------------------------------------------------------
// Reading. Each reader takes the key path it reports in errors ("rayleigh.density.lower").

[[noreturn]] void Fail(const std::string& message) { throw Error(message); }

std::string Join(const std::string& path, const std::string& key) {
  return path.empty() ? key : path + "." + key;
}

// Throws for the first key of `object` that is not in `known`.
void CheckKeys(const Json& object, const std::string& path,
               std::initializer_list<std::string_view> known) {
  for (const auto& item : object.items()) {
    bool found = false;
    for (std::string_view k : known) found = found || item.key() == k;
    if (!found) Fail("unknown key '" + Printable(Join(path, item.key())) + "'");
  }
}

void CheckObject(const Json& value, const std::string& path) {
  if (!value.is_object()) Fail(path + " must be an object");
}

void ReadNumber(const Json& object, const std::string& path, const char* key, double& out) {
  const auto it = object.find(key);
  if (it == object.end()) return;
  if (!it->is_number()) Fail(Join(path, key) + " must be a number");
  out = it->get<double>();
}

// A per-channel vector: an array of numbers, or one number for every channel.
void ReadPerChannel(const Json& object, const std::string& path, const char* key,
                    std::size_t channel_count, std::vector<double>& out) {
  const auto it = object.find(key);
  if (it == object.end()) return;
  const std::string full_key = Join(path, key);
  if (it->is_number()) {
    out.assign(channel_count, it->get<double>());
    return;
  }
  const std::string type_error = full_key + " must be a number or an array of numbers";
  if (!it->is_array()) Fail(type_error);
  std::vector<double> values;
  values.reserve(it->size());
  for (const Json& element : *it) {
    if (!element.is_number()) Fail(type_error);
    values.push_back(element.get<double>());
  }
  out = std::move(values);
}

void ReadLayer(const Json& object, const std::string& path, DensityLayer& layer) {
  CheckObject(object, path);
  CheckKeys(object, path,
            {"width_m", "exp_term", "exp_scale_per_m", "linear_term_per_m", "constant_term"});
  ReadNumber(object, path, "width_m", layer.width_m);
  ReadNumber(object, path, "exp_term", layer.exp_term);
  ReadNumber(object, path, "exp_scale_per_m", layer.exp_scale_per_m);
  ReadNumber(object, path, "linear_term_per_m", layer.linear_term_per_m);
  ReadNumber(object, path, "constant_term", layer.constant_term);
}

// [[altitude_m, density], ...]: at least one knot (Validate checks the rest).
std::vector<DensityKnot> ReadTable(const Json& value, const std::string& path) {
  const std::string type_error = path + " must be an array of [altitude_m, density] pairs";
  if (!value.is_array() || value.empty()) Fail(type_error);
  std::vector<DensityKnot> knots;
  knots.reserve(value.size());
  for (const Json& pair : value) {
    if (!pair.is_array() || pair.size() != 2 || !pair[0].is_number() || !pair[1].is_number()) Fail(type_error);
    knots.push_back(DensityKnot{pair[0].get<double>(), pair[1].get<double>()});
  }
  return knots;
}

// [[angle_deg, value], ...]: at least one sample (Validate checks the rest).
std::vector<PhaseSample> ReadPhaseTable(const Json& value, const std::string& path) {
  const std::string type_error = path + " must be an array of [angle_deg, value] pairs";
  if (!value.is_array() || value.empty()) Fail(type_error);
  std::vector<PhaseSample> samples;
  samples.reserve(value.size());
  for (const Json& pair : value) {
    if (!pair.is_array() || pair.size() != 2 || !pair[0].is_number() || !pair[1].is_number()) Fail(type_error);
    samples.push_back(PhaseSample{pair[0].get<double>(), pair[1].get<double>()});
  }
  return samples;
}

PhaseFunction ParsePhaseFunction(const Json& value, const std::string& key) {
  if (!value.is_string()) Fail(key + " must be a string");
  const std::string name = value.get<std::string>();
  std::string known;
  for (PhaseFunction phase : kPhaseFunctions) {
    if (name == ToString(phase)) return phase;
    known += (known.empty() ? "" : ", ") + std::string(ToString(phase));
  }
  Fail(key + ": unknown phase function '" + Printable(name) + "' (known: " + known + ")");
}

Geometry ParseGeometry(const Json& value, const std::string& key) {
  if (!value.is_string()) Fail(key + " must be a string");
  const std::string name = value.get<std::string>();
  std::string known;
  for (Geometry geometry : kGeometries) {
    if (name == ToString(geometry)) return geometry;
    known += (known.empty() ? "" : ", ") + std::string(ToString(geometry));
  }
  Fail(key + ": unknown geometry '" + Printable(name) + "' (known: " + known + ")");
}

void ReadMedium(const Json& object, const std::string& path, std::size_t channel_count,
                Medium& medium) {
  CheckObject(object, path);
  CheckKeys(object, path,
            {"scattering_per_m", "absorption_per_m", "phase_function", "phase_g", "phase_table", "density"});
  ReadPerChannel(object, path, "scattering_per_m", channel_count, medium.scattering_per_m);
  ReadPerChannel(object, path, "absorption_per_m", channel_count, medium.absorption_per_m);
  if (const auto it = object.find("phase_function"); it != object.end()) {
    medium.phase = ParsePhaseFunction(*it, Join(path, "phase_function"));
    // An analytic phase function given for a medium whose phase was tabulated replaces the table.
    if (medium.phase != PhaseFunction::kTabulated) medium.phase_table.clear();
  }
  ReadNumber(object, path, "phase_g", medium.phase_g);
  if (const auto it = object.find("phase_table"); it != object.end()) {
    medium.phase_table = ReadPhaseTable(*it, Join(path, "phase_table"));
  }
  if (const auto it = object.find("density"); it != object.end()) {
    const std::string density_path = Join(path, "density");
    CheckObject(*it, density_path);
    CheckKeys(*it, density_path, {"lower", "upper", "table"});
    if (const auto table = it->find("table"); table != it->end()) {
      if (it->contains("lower") || it->contains("upper")) {
        Fail(density_path + " holds either a table or lower/upper layers, not both");
      }
      medium.density = DensityProfile::Tabulated(ReadTable(*table, Join(density_path, "table")));
      return;
    }
    // Layers given for a medium whose profile was tabulated replace the table.
    if (medium.density.tabulated()) medium.density = DensityProfile{};
    if (const auto lower = it->find("lower"); lower != it->end()) {
      ReadLayer(*lower, Join(density_path, "lower"), medium.density.lower);
    }
    if (const auto upper = it->find("upper"); upper != it->end()) {
      ReadLayer(*upper, Join(density_path, "upper"), medium.density.upper);
    }
  }
}

// {"type": "urban", "aod_550": 0.3, "angstrom_exponent": 1.2, "visibility_km": 20,
//  "linke_turbidity": 3, "phase": "opac"}: every key optional.
AerosolRequest ReadAerosol(const Json& object) {
  const std::string path = "aerosol";
  CheckObject(object, path);
  CheckKeys(object, path, {"type", "aod_550", "angstrom_exponent", "visibility_km", "linke_turbidity", "phase"});
  AerosolRequest request;
  if (const auto it = object.find("type"); it != object.end()) {
    if (!it->is_string()) Fail("aerosol.type must be a string");
    request.type = it->get<std::string>();
  }
  if (const auto it = object.find("phase"); it != object.end()) {
    if (!it->is_string()) Fail("aerosol.phase must be a string");
    request.phase = it->get<std::string>();
  }
  const auto read = [&](const char* key, std::optional<double>& out) {
    if (object.contains(key)) {
      double value = 0.0;
      ReadNumber(object, path, key, value);
      out = value;
    }
  };
  read("aod_550", request.aod_550);
  read("angstrom_exponent", request.angstrom_exponent);
  read("visibility_km", request.visibility_km);
  read("linke_turbidity", request.linke_turbidity);
  return request;
}

// nlohmann's message without its "[json.exception.parse_error.101] " tag, on one line.
std::string ParseErrorMessage(const Json::parse_error& error) {
  std::string message = error.what();
  if (!message.empty() && message.front() == '[') {
    const std::size_t end = message.find("] ");
    if (end != std::string::npos) message.erase(0, end + 2);
  }
  for (char& c : message) {
    if (c == '\n' || c == '\r') c = ' ';
  }
  return "malformed JSON (byte " + std::to_string(error.byte) + "): " + message;
}

}  // namespace

std::string ToJson(const AtmosphereParameters& p) {
  OrderedJson j;
  j["preset"] = p.name;
  j["geometry"] = std::string(ToString(p.geometry));
  j["ground_radius_m"] = p.ground_radius_m;
  j["top_radius_m"] = p.top_radius_m;
  j["wavelengths_nm"] = p.wavelengths_nm;
  j["rayleigh"] = MediumToJson(p.rayleigh);
  j["mie"] = MediumToJson(p.mie);
  j["ozone"] = MediumToJson(p.ozone);
  // Only when given (the presets without water vapour have empty vectors), so that the seed
  // presets' JSON and hashes stay what they were.
  if (!p.water_vapor.absorption_per_m.empty()) j["water_vapor"] = MediumToJson(p.water_vapor);
  j["ground_albedo"] = p.ground_albedo;
  j["sun_angular_radius_rad"] = p.sun_angular_radius_rad;
  j["sun_limb_darkening"] = p.sun_limb_darkening;
  j["solar_irradiance"] = p.solar_irradiance;
  j["exposure"] = p.exposure;
  j["observer_altitude_m"] = p.observer_altitude_m;
  // Only when it differs from the default, so that the presets' JSON and hashes stay what they were.
  if (!(p.night_sky == NightSkySettings{})) {
    OrderedJson night;
    night["enabled"] = p.night_sky.enabled;
    night["airglow_scale"] = p.night_sky.airglow_scale;
    night["airglow_altitude_m"] = p.night_sky.airglow_altitude_m;
    night["airglow_thickness_m"] = p.night_sky.airglow_thickness_m;
    night["zodiacal_scale"] = p.night_sky.zodiacal_scale;
    night["starlight_scale"] = p.night_sky.starlight_scale;
    j["night_sky"] = night;
  }
  return j.dump(2) + "\n";
}

AtmosphereParameters FromJson(std::string_view json_text) {
  // JSON text holds no NUL; the parser stopped at one and ignored the bytes after it.
  if (const std::size_t nul = json_text.find('\0'); nul != std::string_view::npos) {
    Fail("malformed JSON (byte " + std::to_string(nul + 1) + "): a NUL byte in the text");
  }
  Json root;
  try {
    root = Json::parse(json_text.begin(), json_text.end());
  } catch (const Json::parse_error& error) {
    Fail(ParseErrorMessage(error));
  } catch (const Json::exception& error) {
    // e.g. out_of_range.406 for 1e400, a number beyond double: one line, without the library's tag.
    std::string message = error.what();
    if (!message.empty() && message.front() == '[') {
      const std::size_t end = message.find("] ");
      if (end != std::string::npos) message.erase(0, end + 2);
    }
    Fail("malformed JSON: " + message);
  }
  if (!root.is_object()) Fail("the parameters must be a JSON object");
  CheckKeys(root, "",
            {"preset", "geometry", "ground_radius_m", "top_radius_m", "wavelengths_nm", "rayleigh",
             "mie", "ozone", "water_vapor", "ground_albedo", "sun_angular_radius_rad", "sun_limb_darkening", "solar_irradiance",
             "exposure", "observer_altitude_m", "aerosol", "night_sky"});

  std::string preset_name(kDefaultPreset);
  if (const auto it = root.find("preset"); it != root.end()) {
    if (!it->is_string()) Fail("preset must be a string");
    preset_name = it->get<std::string>();
  }
  const AtmosphereParameters preset =
      Preset(preset_name == kCustomName ? kDefaultPreset : std::string_view(preset_name));
  AtmosphereParameters p = preset;

  if (const auto it = root.find("geometry"); it != root.end()) {
    p.geometry = ParseGeometry(*it, "geometry");
  }
  ReadNumber(root, "", "ground_radius_m", p.ground_radius_m);
  ReadNumber(root, "", "top_radius_m", p.top_radius_m);
  // Wavelengths first: they fix the channel count that single numbers broadcast to.
  ReadPerChannel(root, "", "wavelengths_nm", 1, p.wavelengths_nm);
  const std::size_t channel_count = p.channel_count();
  if (const auto it = root.find("rayleigh"); it != root.end()) {
    ReadMedium(*it, "rayleigh", channel_count, p.rayleigh);
  }
  if (const auto it = root.find("mie"); it != root.end()) {
    ReadMedium(*it, "mie", channel_count, p.mie);
  }
  if (const auto it = root.find("ozone"); it != root.end()) {
    ReadMedium(*it, "ozone", channel_count, p.ozone);
  }
  if (const auto it = root.find("water_vapor"); it != root.end()) {
    // A preset without water vapour has empty vectors: none in every channel until given.
    if (p.water_vapor.absorption_per_m.empty()) {
      p.water_vapor.scattering_per_m.assign(channel_count, 0.0);
      p.water_vapor.absorption_per_m.assign(channel_count, 0.0);
    }
    ReadMedium(*it, "water_vapor", channel_count, p.water_vapor);
  }
  ReadPerChannel(root, "", "ground_albedo", channel_count, p.ground_albedo);
  ReadNumber(root, "", "sun_angular_radius_rad", p.sun_angular_radius_rad);
  if (const auto it = root.find("sun_limb_darkening"); it != root.end()) {
    if (!it->is_boolean()) Fail("sun_limb_darkening must be true or false");
    p.sun_limb_darkening = it->get<bool>();
  }
  ReadPerChannel(root, "", "solar_irradiance", channel_count, p.solar_irradiance);
  ReadNumber(root, "", "exposure", p.exposure);
  ReadNumber(root, "", "observer_altitude_m", p.observer_altitude_m);
  if (const auto it = root.find("night_sky"); it != root.end()) {
    CheckObject(*it, "night_sky");
    CheckKeys(*it, "night_sky",
              {"enabled", "airglow_scale", "airglow_altitude_m", "airglow_thickness_m", "zodiacal_scale",
               "starlight_scale"});
    if (const auto enabled = it->find("enabled"); enabled != it->end()) {
      if (!enabled->is_boolean()) Fail("night_sky.enabled must be true or false");
      p.night_sky.enabled = enabled->get<bool>();
    }
    ReadNumber(*it, "night_sky", "airglow_scale", p.night_sky.airglow_scale);
    ReadNumber(*it, "night_sky", "airglow_altitude_m", p.night_sky.airglow_altitude_m);
    ReadNumber(*it, "night_sky", "airglow_thickness_m", p.night_sky.airglow_thickness_m);
    ReadNumber(*it, "night_sky", "zodiacal_scale", p.night_sky.zodiacal_scale);
    ReadNumber(*it, "night_sky", "starlight_scale", p.night_sky.starlight_scale);
  }
  // "aerosol" replaces the Mie medium by an OPAC aerosol (docs/aerosols.md), after the other keys.
  if (const auto it = root.find("aerosol"); it != root.end()) ApplyAerosolRequest(p, ReadAerosol(*it));

  // The name says which preset the values are: the preset's name when every value equals it
  // (whatever keys the document repeats), "custom" as soon as one differs.
  p.name = preset.name;
  if (!(p == preset)) p.name = std::string(kCustomName);

  Validate(p);
  return p;
}

AtmosphereParameters LoadParametersFile(const std::filesystem::path& path) {
  // Bounded: a regular file of at most 64 MiB ("cannot read config 'PATH': is a directory", ...);
  // /dev/zero ended in std::bad_alloc.
  const std::string text = ReadFileBounded(path, "config ");
  try {
    return FromJson(text);
  } catch (const Error& error) {
    Fail("config '" + path.string() + "': " + error.what());
  }
}

}  // namespace atmo
