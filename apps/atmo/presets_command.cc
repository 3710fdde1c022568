// `atmo presets`: lists the presets, or prints one as JSON that --config accepts back.
#include <cstdio>
#include <map>

#include "atmo/error.h"
#include "commands.h"

namespace atmo::cli {

namespace {

// Where each preset comes from (docs/design.md §3); the physical summary is derived from its values.
std::string PresetSource(const std::string& name) {
  static const std::map<std::string, std::string> kSources = {
      {"earth", "Earth, after Hillaire 2020 / Bruneton 2017"},
      {"earth-spectral", "earth at 15 wavelengths, each medium from its physics (docs/spectral.md)"},
      {"atmosphere-plus", "Earth as in the Atmosphere Plus seed"},
      {"simple", "homogeneous half-space of the simple seed"},
      {"us-standard", "US Standard Atmosphere 1976 air, ozone, water vapour and O2 with OPAC continental-average aerosol (docs/validation.md)"},
      {"tropical", "AFGL 1986 tropical air, ozone, water vapour and O2 with OPAC continental-average aerosol"},
      {"midlatitude-summer", "AFGL 1986 mid-latitude summer air, ozone, water vapour and O2 with OPAC continental-average aerosol"},
      {"midlatitude-winter", "AFGL 1986 mid-latitude winter air, ozone, water vapour and O2 with OPAC continental-average aerosol"},
      {"subarctic-summer", "AFGL 1986 sub-arctic summer air, ozone, water vapour and O2 with OPAC continental-average aerosol"},
      {"subarctic-winter", "AFGL 1986 sub-arctic winter air, ozone, water vapour and O2 with OPAC continental-average aerosol"},
  };
  const auto found = kSources.find(name);
  return found == kSources.end() ? name : found->second;
}

std::string PresetSummary(const AtmosphereParameters& p) {
  std::string channels;
  const std::size_t n = p.wavelengths_nm.size();
  if (n > 4) {  // a spectral preset: its range
    channels = Format("%zu over %.10g-%.10g", n, p.wavelengths_nm.front(), p.wavelengths_nm.back());
  } else {
    for (std::size_t c = 0; c < n; ++c) channels += Format(c == 0 ? "%.10g" : ", %.10g", p.wavelengths_nm[c]);
  }
  if (p.geometry == Geometry::kHalfSpace) return "half-space; channels " + channels + " nm";
  std::string media;
  for (const auto& [name, medium] : {std::pair<const char*, const Medium*>{"rayleigh", &p.rayleigh},
                                     {"mie", &p.mie},
                                     {"ozone", &p.ozone},
                                     {"water_vapor", &p.water_vapor}}) {
    if (medium->present()) media += std::string(media.empty() ? "" : "+") + name;
  }
  return Format("ground %.10g km, top %.10g km; channels %s nm; %s", p.ground_radius_m / 1e3,
                p.top_radius_m / 1e3, channels.c_str(), media.c_str());
}

}  // namespace

int RunPresets(const CommonOptions& common, const PresetsCommand& command) {
  if (!command.dump.empty()) {
    std::string json = ToJson(Preset(command.dump));
    if (json.empty() || json.back() != '\n') json += '\n';
    std::fputs(json.c_str(), stdout);
    return 0;
  }
  for (const std::string& name : PresetNames()) {
    const AtmosphereParameters parameters = Preset(name);
    std::printf("%-18s %s (%s)\n", name.c_str(), PresetSource(name).c_str(),
                PresetSummary(parameters).c_str());
  }
  return 0;
}

}  // namespace atmo::cli
