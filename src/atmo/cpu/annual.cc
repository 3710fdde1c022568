// Annual skies calibrated to a weather file's hours (include/atmo/annual.h).
#include "atmo/annual.h"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <limits>
#include <mutex>
#include <numbers>
#include <string>

#include <oneapi/tbb/parallel_for.h>

#include "atmo/aerosol.h"
#include "atmo/calibration.h"
#include "atmo/colour.h"
#include "atmo/error.h"
#include "atmo/render.h"
#include "atmo/spectrum.h"
#include "atmo/sun_position.h"
#include "printable.h"

namespace atmo {

namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

// CIE standard overcast sky (CIE S 011/E:2003, sky type 1; Moon and Spencer 1942): radiance
// (1 + 2 sin(altitude)) / 3 times the zenith's, the same at every wavelength (relative to the
// solar spectrum). Its horizontal irradiance is 7 pi / 9 times the zenith radiance.
class OvercastSky : public SkyView {
 public:
  OvercastSky(const glm::dvec3& sun, std::size_t channels) : SkyView(0.0, sun, channels) {}
  void Radiance(const glm::dvec3& view, std::span<double> out) const override {
    const double l = view.z < 0.0 ? 0.0 : (1.0 + 2.0 * view.z) / 3.0;
    std::fill(out.begin(), out.end(), l);
  }
  void Transmittance(const glm::dvec3&, std::span<double> out) const override { std::fill(out.begin(), out.end(), 0.0); }
  void SunDiscRadiance(const glm::dvec3&, std::span<double> out) const override { std::fill(out.begin(), out.end(), 0.0); }
};

// a += w b, per element.
void AddScaled(std::vector<double>& a, const std::vector<double>& b, double w) {
  if (a.empty()) a.assign(b.size(), 0.0);
  for (std::size_t i = 0; i < a.size(); ++i) a[i] += w * b[i];
}

void Accumulate(IrradianceComponents& into, const IrradianceComponents& e, double w) {
  AddScaled(into.direct, e.direct, w);
  AddScaled(into.circumsolar, e.circumsolar, w);
  AddScaled(into.sky_diffuse, e.sky_diffuse, w);
  AddScaled(into.ground_reflected, e.ground_reflected, w);
}

// The map's pixels' directions (inside the circle) and their indices.
struct MapPixels {
  std::vector<glm::dvec3> directions;
  std::vector<std::size_t> pixels;
};

MapPixels SkyMapPixels(int size) {
  MapPixels out;
  for (int y = 0; y < size; ++y) {
    for (int x = 0; x < size; ++x) {
      glm::dvec3 d;
      if (SkyMapDirection(x, y, size, d)) {
        out.directions.push_back(d);
        out.pixels.push_back(static_cast<std::size_t>(y) * size + x);
      }
    }
  }
  return out;
}

}  // namespace

bool SkyMapDirection(int x, int y, int size, glm::dvec3& direction) {
  const double dx = (x + 0.5) / size - 0.5;
  const double dy = 0.5 - (y + 0.5) / size;
  const double r = std::hypot(dx, dy);
  if (r > 0.5) return false;
  const double theta = r * std::numbers::pi;
  const double phi = std::atan2(dx, dy);
  direction = glm::dvec3(std::sin(theta) * std::sin(phi), std::sin(theta) * std::cos(phi), std::cos(theta));
  return true;
}

std::string_view ToString(HourStatus status) {
  switch (status) {
    case HourStatus::kNight: return "night";
    case HourStatus::kMissing: return "missing";
    case HourStatus::kLowSun: return "low-sun";
    case HourStatus::kClear: return "clear";
    case HourStatus::kCloudy: return "cloudy";
    case HourStatus::kOvercast: return "overcast";
    case HourStatus::kDim: return "dim";
  }
  return "unknown";
}

AnnualSkies::AnnualSkies(AtmosphereParameters base, WeatherFile weather, AnnualSettings settings)
    : base_(std::move(base)),
      weather_(std::move(weather)),
      settings_(std::move(settings)),
      patches_(SkyPatches::Reinhart(settings_.sky_subdivision)) {
  const std::vector<double>& a = settings_.aod_nodes;
  const std::vector<double>& w = settings_.albedo_nodes;
  if (a.size() < 2 || w.size() != 2) throw Error("the annual table needs at least 2 optical depths and exactly 2 albedos");
  for (std::size_t i = 0; i < a.size(); ++i) {
    if (!(a[i] >= 0.0 && a[i] <= kMaxAerosolOpticalDepth) || (i > 0 && !(a[i] > a[i - 1]))) {
      throw Error("the table's optical depths must increase within [0, 10]");
    }
  }
  if (!(w[0] > 0.0 && w[0] < w[1] && w[1] <= 1.0)) throw Error("the table's albedos must increase within (0, 1]");
  if (!(settings_.min_single_scattering_albedo >= 0.0 && settings_.min_single_scattering_albedo < w[1])) {
    throw Error("the smallest albedo must be in [0, the largest node)");
  }
  if (settings_.patch_samples < 1 || settings_.patch_samples > 16) throw Error("the samples per patch side must be in [1, 16]");
  if (settings_.sky_map_size < 0 || settings_.sky_map_size > 4096) throw Error("the sky map size must be in [0, 4096]");
  if (!(settings_.min_sun_elevation_deg >= 0.0 && settings_.min_sun_elevation_deg <= 10.0)) {
    throw Error("the lowest calibrated sun elevation must be in [0, 10] degrees");
  }
  if (base_.geometry != Geometry::kSpherical) throw Error("annual skies need a spherical atmosphere");
  const WeatherLocation& l = weather_.location;
  if (!(l.elevation_m >= 0.0 && l.elevation_m < base_.top_radius_m - base_.ground_radius_m)) {
    throw Error("the station's elevation " + FormatNumber(l.elevation_m) + " m must be in the atmosphere (>= 0)");
  }
  ValidateAerosol(AerosolSettings{settings_.aerosol_type, 0.1, kNaN});
  nodes_.resize(a.size() * 2);
}

AnnualSkies::~AnnualSkies() = default;

const Model& AnnualSkies::NodeModel(std::size_t aod_index, std::size_t albedo_index) {
  std::unique_ptr<Model>& slot = nodes_[aod_index * 2 + albedo_index];
  if (!slot) {
    const AtmosphereParameters p = WithAerosol(base_, settings_.aerosol_type, settings_.aod_nodes[aod_index],
                                               settings_.albedo_nodes[albedo_index]);
    slot = CreateModel(settings_.model, p, DaylightModelOptions(settings_.model, settings_.options));
    ++models_built_;
  }
  return *slot;
}

void AnnualSkies::Release(std::size_t below_aod_index) {
  for (std::size_t i = 0; i < below_aod_index && i < settings_.aod_nodes.size(); ++i) {
    nodes_[2 * i].reset();
    nodes_[2 * i + 1].reset();
  }
}

std::vector<HourSky> AnnualSkies::Compute(std::span<const std::size_t> hours,
                                          const std::function<void(std::size_t)>& progress,
                                          const std::function<void(std::span<const HourSky>)>& batch) {
  const std::size_t n = channel_count();
  const SpectralConversion convert(base_.wavelengths_nm);
  const WeatherLocation& place = weather_.location;
  const std::vector<double>& aods = settings_.aod_nodes;
  const std::vector<double>& albedos = settings_.albedo_nodes;
  std::vector<Plane> planes = {Plane::Horizontal(), Plane::FacingSun()};
  planes.insert(planes.end(), settings_.planes.begin(), settings_.planes.end());
  IrradianceSettings irradiance;
  irradiance.patches = &patches_;
  irradiance.patch_samples = settings_.patch_samples;
  irradiance.circumsolar_subdivisions = 6;  // the cells near the sun split 6 x 6: the aureole within 0.35 % of a fine grid
  irradiance.circumsolar_half_angle_deg = settings_.circumsolar_half_angle_deg;
  const double altitude_m = place.elevation_m;

  std::vector<HourSky> out(hours.size());
  std::atomic<std::size_t> done{0};
  std::mutex progress_mutex;
  const auto finished = [&] {
    const std::size_t d = ++done;
    if (progress) {
      const std::lock_guard lock(progress_mutex);
      progress(d);
    }
  };

  const MapPixels map = SkyMapPixels(settings_.sky_map_size);
  // An hour's map from its clear part's relative radiance per map direction (or none) and its
  // overcast part.
  const auto make_map = [&](HourSky& sky, const std::vector<double>* clear_part) {
    const int size = settings_.sky_map_size;
    if (size == 0) return;
    sky.sky_map = Image(size, size, 3);
    std::vector<double> l(n);
    for (std::size_t k = 0; k < map.pixels.size(); ++k) {
      const double overcast = sky.overcast_zenith * (1.0 + 2.0 * map.directions[k].z) / 3.0;
      for (std::size_t c = 0; c < n; ++c) l[c] = overcast + (clear_part ? (*clear_part)[k * n + c] : 0.0);
      const glm::dvec3 rgb = XyzToRadianceRgbInGamut(kMaxLuminousEfficacy * convert.Xyz(l));
      for (int c = 0; c < 3; ++c) sky.sky_map.pixels[map.pixels[k] * 3 + c] = static_cast<float>(rgb[c]);
    }
  };

  // The overcast part of an hour, per unit zenith radiance (sun_scale applied by the caller).
  const auto overcast_unit = [&](const glm::dvec3& sun) {
    const OvercastSky sky(sun, n);
    return ComputeIrradiance(sky, base_, planes, irradiance);
  };
  const auto lux = [&](const std::vector<double>& v) { return convert.Luminance(v); };

  // Completes an hour from its clear part (scaled by `clear`) and overcast part: the ground, the
  // direct, the patch radiances and the measured-like totals.
  const auto finish = [&](HourSky& sky, const glm::dvec3& sun, std::vector<IrradianceComponents> parts,
                          std::vector<double> patch, const std::vector<double>& direct_normal) {
    // The overcast part carries overcast_lux of diffuse horizontal light (outside the cone).
    if (sky.overcast_lux > 0.0) {
      const IrradianceResult unit = overcast_unit(sun);
      const double z = sky.overcast_lux / lux(unit.planes[0].sky_diffuse);
      sky.overcast_zenith = z;
      for (std::size_t p = 0; p < planes.size(); ++p) Accumulate(parts[p], unit.planes[p], z);
      AddScaled(patch, unit.patch_radiance, z);
    }
    const bool sun_up = sun.z > 0.0;
    for (std::size_t p = 0; p < planes.size(); ++p) {
      parts[p].direct.assign(n, 0.0);
      const double incidence = glm::dot(planes[p].Normal(sun), sun);
      if (sun_up && incidence > 0.0 && !direct_normal.empty()) {
        for (std::size_t c = 0; c < n; ++c) parts[p].direct[c] = direct_normal[c] * incidence;
      }
    }
    // The ground, lit by the horizontal global.
    std::vector<double> ground(n);
    const IrradianceComponents& h = parts[0];
    for (std::size_t c = 0; c < n; ++c) {
      ground[c] = base_.ground_albedo[c] * (h.direct[c] + h.circumsolar[c] + h.sky_diffuse[c]) / std::numbers::pi;
    }
    for (std::size_t p = 0; p < planes.size(); ++p) {
      const double nz = std::clamp(planes[p].Normal(sun).z, -1.0, 1.0);
      parts[p].ground_reflected.resize(n);
      for (std::size_t c = 0; c < n; ++c) parts[p].ground_reflected[c] = ground[c] * std::numbers::pi * 0.5 * (1.0 - nz);
    }
    if (patch.empty()) patch.assign(patches_.count() * n, 0.0);
    if (settings_.sun_in_matrix && sun_up && !direct_normal.empty()) {
      const int i = patches_.Index(sun);
      const double omega = patches_.patches()[static_cast<std::size_t>(i)].solid_angle_sr;
      for (std::size_t c = 0; c < n; ++c) patch[static_cast<std::size_t>(i) * n + c] += direct_normal[c] / omega;
    }
    sky.patch_radiance = ground;
    sky.patch_radiance.insert(sky.patch_radiance.end(), patch.begin(), patch.end());
    sky.direct_normal_lux = (direct_normal.empty() ? 0.0 : lux(direct_normal)) + lux(parts[1].circumsolar);
    sky.diffuse_horizontal_lux = lux(parts[0].sky_diffuse);
    sky.planes = std::move(parts);
  };

  // Phase 1: the sun, the hours that need no model, and each other hour's optical depth.
  struct Pending {
    std::size_t slot;
    glm::dvec3 sun;
    std::unique_ptr<DirectLight> direct;
    double aod;
    std::size_t bracket;  // aods[bracket] <= aod <= aods[bracket + 1]
  };
  std::vector<Pending> pending;
  for (std::size_t slot = 0; slot < hours.size(); ++slot) {
    if (hours[slot] >= weather_.hours.size()) throw Error("hour index " + std::to_string(hours[slot]) + " is past the file's end");
    const WeatherHour& h = weather_.hours[hours[slot]];
    HourSky& sky = out[slot];
    sky.hour = hours[slot];
    sky.julian_day_utc = MidHourJulianDayUtc(place, h);
    const SunPosition position = ComputeSunPosition(sky.julian_day_utc, place.latitude_deg, place.longitude_deg);
    sky.sun_elevation_deg = position.elevation_deg;
    sky.sun_azimuth_deg = position.azimuth_deg;
    sky.sun_scale = 1.0 / (position.distance_au * position.distance_au);
    sky.aod_550 = sky.single_scattering_albedo_550 = kNaN;
    const glm::dvec3 sun = SunDirection(position.elevation_deg, position.azimuth_deg);
    const double dn = h.direct_normal_lux, dh = h.diffuse_horizontal_lux;
    if (std::isnan(dn) || std::isnan(dh)) {
      sky.status = HourStatus::kMissing;
      finished();
      continue;
    }
    if (dh <= 0.0 && (position.elevation_deg <= 0.0 || dn <= 0.0)) {
      sky.status = HourStatus::kNight;
      finished();
      continue;
    }
    if (position.elevation_deg < settings_.min_sun_elevation_deg || dh <= 0.0) {
      sky.status = HourStatus::kLowSun;
      sky.overcast_lux = dh;
      finish(sky, sun, std::vector<IrradianceComponents>(planes.size(), IrradianceComponents{
                                                                           std::vector<double>(n, 0.0), std::vector<double>(n, 0.0),
                                                                           std::vector<double>(n, 0.0), std::vector<double>(n, 0.0)}),
             {}, {});
      make_map(sky, nullptr);
      finished();
      continue;
    }
    Pending p{slot, sun, std::make_unique<DirectLight>(base_, settings_.aerosol_type, altitude_m, sun, sky.sun_scale), 0.0, 0};
    p.aod = p.direct->OpticalDepthFor(dn);
    p.bracket = static_cast<std::size_t>(std::upper_bound(aods.begin(), aods.end(), p.aod) - aods.begin());
    p.bracket = std::clamp<std::size_t>(p.bracket, 1, aods.size() - 1) - 1;
    pending.push_back(std::move(p));
  }
  std::stable_sort(pending.begin(), pending.end(), [](const Pending& a, const Pending& b) { return a.bracket < b.bracket; });
  // Hands finished hours to `batch`, then keeps only their scalars: a year of 2305-patch columns
  // would otherwise be held whole (2.4 GB with 15 channels).
  const auto hand_over = [&](const std::vector<std::size_t>& slots) {
    if (!batch || slots.empty()) return;
    std::vector<HourSky> group;
    for (std::size_t slot : slots) {
      group.push_back(std::move(out[slot]));
      HourSky& kept = out[slot];
      const HourSky& full = group.back();
      kept.hour = full.hour;
      kept.status = full.status;
      kept.julian_day_utc = full.julian_day_utc;
      kept.sun_elevation_deg = full.sun_elevation_deg;
      kept.sun_azimuth_deg = full.sun_azimuth_deg;
      kept.sun_scale = full.sun_scale;
      kept.aod_550 = full.aod_550;
      kept.single_scattering_albedo_550 = full.single_scattering_albedo_550;
      kept.clear_fraction = full.clear_fraction;
      kept.overcast_lux = full.overcast_lux;
      kept.direct_normal_lux = full.direct_normal_lux;
      kept.diffuse_horizontal_lux = full.diffuse_horizontal_lux;
      kept.overcast_zenith = full.overcast_zenith;
    }
    batch(group);
  };
  {
    std::vector<char> modelled(hours.size(), 0);
    for (const Pending& p : pending) modelled[p.slot] = 1;
    std::vector<std::size_t> slots;
    for (std::size_t slot = 0; slot < hours.size(); ++slot) {
      if (!modelled[slot]) slots.push_back(slot);
    }
    hand_over(slots);
  }

  // Phase 2: by optical-depth bracket, its four nodes built once.
  std::size_t start = 0;
  while (start < pending.size()) {
    const std::size_t b = pending[start].bracket;
    std::size_t end = start;
    while (end < pending.size() && pending[end].bracket == b && end - start < 256) ++end;
    Release(b);
    const Model* models[2][2] = {{&NodeModel(b, 0), &NodeModel(b, 1)}, {&NodeModel(b + 1, 0), &NodeModel(b + 1, 1)}};
    oneapi::tbb::parallel_for(start, end, [&](std::size_t k) {
      Pending& p = pending[k];
      HourSky& sky = out[p.slot];
      const WeatherHour& h = weather_.hours[sky.hour];
      const double dn = h.direct_normal_lux, dh = h.diffuse_horizontal_lux;
      IrradianceSettings s = irradiance;
      s.sun_scale = sky.sun_scale;
      IrradianceResult node[2][2];
      std::unique_ptr<SkyView> views[2][2];
      for (int i = 0; i < 2; ++i) {
        for (int j = 0; j < 2; ++j) {
          views[i][j] = models[i][j]->View(altitude_m, p.sun);
          node[i][j] = ComputeIrradiance(*views[i][j], base_, planes, s);
        }
      }
      const double a0 = aods[b], a1 = aods[b + 1];
      const double w0 = albedos[0], w1 = albedos[1];
      const bool overcast = p.aod >= aods.back();
      double clear = 1.0;
      double aod = p.aod;
      // The blended diffuse horizontal lux at (f, g) is linear in g.
      const auto diffuse_at = [&](double f, double g) {
        const double d00 = lux(node[0][0].planes[0].sky_diffuse), d01 = lux(node[0][1].planes[0].sky_diffuse);
        const double d10 = lux(node[1][0].planes[0].sky_diffuse), d11 = lux(node[1][1].planes[0].sky_diffuse);
        return clear * ((1 - f) * ((1 - g) * d00 + g * d01) + f * ((1 - g) * d10 + g * d11));
      };
      const auto circumsolar_at = [&](double f, double g) {
        const double c00 = lux(node[0][0].planes[1].circumsolar), c01 = lux(node[0][1].planes[1].circumsolar);
        const double c10 = lux(node[1][0].planes[1].circumsolar), c11 = lux(node[1][1].planes[1].circumsolar);
        return clear * ((1 - f) * ((1 - g) * c00 + g * c01) + f * ((1 - g) * c10 + g * c11));
      };
      const double g_max = (1.0 - w0) / (w1 - w0);
      if (overcast) {
        // The share of the clearest-scattering sky at the table's last optical depth whose disc and
        // aureole give the measured direct light.
        aod = aods.back();
        clear = 1.0;
        clear = dn / (p.direct->Lux(aod) + circumsolar_at(1.0, g_max));
      }
      const double g_min = (settings_.min_single_scattering_albedo - w0) / (w1 - w0);
      double f = 0.0, g = 0.0;
      HourStatus status = HourStatus::kClear;
      for (int pass = 0; pass < 2; ++pass) {
        f = std::clamp((aod - a0) / (a1 - a0), -0.5, 1.5);
        const double d_0 = diffuse_at(f, 0.0), d_1 = diffuse_at(f, 1.0);
        g = d_1 != d_0 ? (dh - d_0) / (d_1 - d_0) : g_max;
        status = overcast ? HourStatus::kOvercast : HourStatus::kClear;
        if (g > g_max) {
          g = g_max;
          if (!overcast) status = HourStatus::kCloudy;
        } else if (g < g_min) {
          g = g_min;
          status = HourStatus::kDim;
        }
        if (overcast) break;
        // The pyrheliometer counts the aureole as direct light: the disc's share is the rest.
        aod = p.direct->OpticalDepthFor(std::max(dn - circumsolar_at(f, g), 0.0));
      }
      const double weights[2][2] = {{(1 - f) * (1 - g), (1 - f) * g}, {f * (1 - g), f * g}};
      std::vector<IrradianceComponents> parts(planes.size());
      std::vector<double> patch;
      for (int i = 0; i < 2; ++i) {
        for (int j = 0; j < 2; ++j) {
          for (std::size_t q = 0; q < planes.size(); ++q) Accumulate(parts[q], node[i][j].planes[q], clear * weights[i][j]);
          AddScaled(patch, node[i][j].patch_radiance, clear * weights[i][j]);
        }
      }
      sky.status = status;
      sky.aod_550 = aod;
      sky.single_scattering_albedo_550 = w0 + g * (w1 - w0);
      sky.clear_fraction = clear;
      sky.overcast_lux = status == HourStatus::kCloudy || status == HourStatus::kOvercast
                             ? std::max(0.0, dh - diffuse_at(f, g))
                             : 0.0;
      std::vector<double> direct_normal = p.direct->DirectNormal(aod);
      for (double& v : direct_normal) v *= clear;
      finish(sky, p.sun, std::move(parts), std::move(patch), direct_normal);
      if (settings_.sky_map_size > 0) {
        std::vector<double> clear_part(map.directions.size() * n, 0.0);
        std::vector<float> radiance(map.directions.size() * n);
        for (int i = 0; i < 2; ++i) {
          for (int j = 0; j < 2; ++j) {
            if (weights[i][j] == 0.0) continue;
            views[i][j]->RadianceBatch(map.directions, RadianceTerms{false, false}, radiance);
            const double w = clear * weights[i][j] * sky.sun_scale;
            for (std::size_t k = 0; k < clear_part.size(); ++k) clear_part[k] += w * radiance[k];
          }
        }
        make_map(sky, &clear_part);
      }
      finished();
    });
    std::vector<std::size_t> slots;
    for (std::size_t k = start; k < end; ++k) slots.push_back(pending[k].slot);
    hand_over(slots);
    start = end;
  }
  Release(aods.size());
  return out;
}

}  // namespace atmo
