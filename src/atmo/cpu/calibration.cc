// Calibration of a clear sky to a measured direct-normal and diffuse-horizontal illuminance
// (include/atmo/calibration.h).
#include "atmo/calibration.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <optional>

#include "atmo/aerosol.h"
#include "atmo/colour.h"
#include "atmo/error.h"
#include "atmo/irradiance.h"
#include "atmo/sky_patches.h"
#include "physics/shared_parameters.h"
#include "printable.h"

namespace atmo {

namespace {

// Trapezoids of the transmittance towards the sun: far finer than any model's table, so that the
// direct light is fitted to the optical depth itself.
constexpr int kQuadratureSteps = 1000;

double ValueAt550(const AtmosphereParameters& p, const std::vector<double>& values) {
  const std::vector<double>& w = p.wavelengths_nm;
  std::size_t below = w.size(), above = w.size();
  for (std::size_t c = 0; c < w.size(); ++c) {
    if (w[c] <= 550.0 && (below == w.size() || w[c] > w[below])) below = c;
    if (w[c] >= 550.0 && (above == w.size() || w[c] < w[above])) above = c;
  }
  if (below == w.size()) return values[above];
  if (above == w.size() || above == below) return values[below];
  const double f = (550.0 - w[below]) / (w[above] - w[below]);
  return (1.0 - f) * values[below] + f * values[above];
}

// Transmittance towards `sun` per channel by quadrature; 0 when the ray meets the ground.
std::vector<double> SunTransmittance(const AtmosphereParameters& p, double altitude_m, const glm::dvec3& sun) {
  const std::size_t n = p.channel_count();
  std::vector<double> t(n, 0.0);
  const double r = p.ground_radius_m + altitude_m;
  const double mu = glm::normalize(sun).z;
  const double R = p.ground_radius_m;
  if (mu < 0.0 && r * r * (mu * mu - 1.0) + R * R >= 0.0) return t;
  ScatterBatches(ChannelBatchCount(n), t, [&](std::size_t b) {
    return shared::ComputeTransmittanceToTopAtmosphereBoundary(ToSharedParameters(p, b), r, mu, kQuadratureSteps);
  });
  return t;
}

struct Evaluation {
  double albedo = 0.0;
  double diffuse_lux = 0.0;      // horizontal, outside the circumsolar cone
  double circumsolar_lux = 0.0;  // on a plane facing the sun
  double direct_lux = 0.0;       // the disc's, from the model's own transmittance
};

std::string Lux(double value) {
  char buffer[32];
  std::snprintf(buffer, sizeof buffer, "%.0f lux", value);
  return buffer;
}

std::string Fixed(double value, int digits) {
  char buffer[32];
  std::snprintf(buffer, sizeof buffer, "%.*f", digits, value);
  return buffer;
}

}  // namespace

std::string_view ToString(CalibrationStatus status) {
  switch (status) {
    case CalibrationStatus::kClear: return "clear";
    case CalibrationStatus::kTooMuchDiffuse: return "too-much-diffuse";
    case CalibrationStatus::kTooLittleDiffuse: return "too-little-diffuse";
    case CalibrationStatus::kTooMuchDirect: return "too-much-direct";
    case CalibrationStatus::kTooLittleDirect: return "too-little-direct";
    case CalibrationStatus::kNotConverged: return "not-converged";
  }
  return "unknown";
}

ModelOptions DaylightModelOptions(const std::string& model, ModelOptions options) {
  if (model == "source4d" && options.find("sky_view") == options.end()) options["sky_view"] = "off";
  return options;
}

double MieSingleScatteringAlbedo550(const AtmosphereParameters& p) {
  std::vector<double> albedo(p.channel_count(), 1.0);
  for (std::size_t c = 0; c < albedo.size(); ++c) {
    const double extinction = p.mie.extinction_per_m(c);
    if (extinction > 0.0) albedo[c] = p.mie.scattering_per_m[c] / extinction;
  }
  return ValueAt550(p, albedo);
}

AtmosphereParameters WithAerosol(const AtmosphereParameters& base, const std::string& type, double aod_550,
                                 double single_scattering_albedo_550) {
  if (!(std::isfinite(aod_550) && aod_550 >= 0.0 && aod_550 <= kMaxAerosolOpticalDepth)) {
    throw Error("aerosol optical depth " + FormatNumber(aod_550) + " at 550 nm is outside [0, 10]");
  }
  AtmosphereParameters p = base;
  AerosolSettings aerosol;
  aerosol.type = type;
  const double typical = AerosolTypicalOpticalDepth(type);
  aerosol.aod_550 = typical;
  ApplyAerosol(p, aerosol);
  const double k = aod_550 / typical;
  for (std::size_t c = 0; c < p.channel_count(); ++c) {
    p.mie.scattering_per_m[c] *= k;
    p.mie.absorption_per_m[c] *= k;
  }
  if (std::isnan(single_scattering_albedo_550) || aod_550 == 0.0) return p;
  if (!(single_scattering_albedo_550 >= 0.0 && single_scattering_albedo_550 <= 1.0)) {
    throw Error("the single-scattering albedo must be in [0, 1], got " + FormatNumber(single_scattering_albedo_550));
  }
  const double shift = single_scattering_albedo_550 - MieSingleScatteringAlbedo550(p);
  for (std::size_t c = 0; c < p.channel_count(); ++c) {
    const double extinction = p.mie.extinction_per_m(c);
    if (!(extinction > 0.0)) continue;
    const double albedo = std::clamp(p.mie.scattering_per_m[c] / extinction + shift, 0.0, 1.0);
    p.mie.scattering_per_m[c] = albedo * extinction;
    p.mie.absorption_per_m[c] = extinction - p.mie.scattering_per_m[c];
  }
  return p;
}

DirectLight::DirectLight(const AtmosphereParameters& base, const std::string& type, double altitude_m,
                         const glm::dvec3& sun, double sun_scale)
    : sun_scale_(sun_scale) {
  const double typical = AerosolTypicalOpticalDepth(type);
  const AtmosphereParameters with = WithAerosol(base, type, typical, std::numeric_limits<double>::quiet_NaN());
  AtmosphereParameters without = with;
  std::fill(without.mie.scattering_per_m.begin(), without.mie.scattering_per_m.end(), 0.0);
  std::fill(without.mie.absorption_per_m.begin(), without.mie.absorption_per_m.end(), 0.0);
  const std::vector<double> t_with = SunTransmittance(with, altitude_m, sun);
  air_ = SunTransmittance(without, altitude_m, sun);
  aerosol_.resize(air_.size());
  for (std::size_t c = 0; c < air_.size(); ++c) {
    aerosol_[c] = air_[c] > 0.0 && t_with[c] > 0.0 ? std::log(air_[c] / t_with[c]) / typical
                                                   : std::numeric_limits<double>::infinity();
  }
  const SpectralConversion convert(base.wavelengths_nm);
  weights_.resize(air_.size());
  for (std::size_t c = 0; c < air_.size(); ++c) {
    std::vector<double> unit(air_.size(), 0.0);
    unit[c] = 1.0;
    weights_[c] = convert.Luminance(unit);
  }
}

std::vector<double> DirectLight::DirectNormal(double aod_550) const {
  std::vector<double> out(air_.size());
  for (std::size_t c = 0; c < out.size(); ++c) {
    out[c] = air_[c] > 0.0 ? sun_scale_ * air_[c] * std::exp(-aod_550 * aerosol_[c]) : 0.0;
  }
  return out;
}

double DirectLight::Lux(double aod_550) const {
  const std::vector<double> t = DirectNormal(aod_550);
  double sum = 0.0;
  for (std::size_t c = 0; c < t.size(); ++c) sum += weights_[c] * t[c];
  return sum;
}

double DirectLight::OpticalDepthFor(double lux) const {
  double lo = 0.0, hi = kMaxAerosolOpticalDepth;
  if (lux >= Lux(lo)) return lo;
  if (lux <= Lux(hi)) return hi;
  for (int i = 0; i < 64 && hi - lo > 1e-9; ++i) {
    const double mid = 0.5 * (lo + hi);
    (Lux(mid) > lux ? lo : hi) = mid;
  }
  return 0.5 * (lo + hi);
}

CalibrationResult CalibrateClearSky(const AtmosphereParameters& base, double altitude_m, const glm::dvec3& sun,
                                    const DaylightMeasurement& measured, const CalibrationSettings& settings) {
  if (base.geometry != Geometry::kSpherical) throw Error("calibration needs a spherical atmosphere");
  if (!(std::isfinite(measured.direct_normal_lux) && measured.direct_normal_lux >= 0.0)) {
    throw Error("the direct normal illuminance must be finite and >= 0, got " + FormatNumber(measured.direct_normal_lux));
  }
  if (!(std::isfinite(measured.diffuse_horizontal_lux) && measured.diffuse_horizontal_lux > 0.0)) {
    throw Error("the diffuse horizontal illuminance must be finite and > 0, got " +
                FormatNumber(measured.diffuse_horizontal_lux));
  }
  if (!(std::isfinite(altitude_m) && altitude_m >= 0.0 && altitude_m < base.top_radius_m - base.ground_radius_m)) {
    throw Error("the station's altitude must be in the atmosphere, got " + FormatNumber(altitude_m) + " m");
  }
  const glm::dvec3 s = glm::normalize(sun);
  if (!(std::isfinite(s.z) && s.z >= std::sin(glm::radians(1.0)))) {
    throw Error("calibration needs the sun at least 1 degree above the horizon");
  }
  const double lo_albedo = settings.min_single_scattering_albedo;
  const double hi_albedo = settings.max_single_scattering_albedo;
  if (!(lo_albedo >= 0.0 && lo_albedo < hi_albedo && hi_albedo <= 1.0)) {
    throw Error("the single-scattering albedo range must lie in [0, 1] with min < max");
  }
  if (!(settings.tolerance > 0.0 && settings.tolerance < 0.5)) throw Error("the calibration tolerance must be in (0, 0.5)");
  if (!(std::isfinite(settings.sun_scale) && settings.sun_scale > 0.0)) throw Error("the sun scale must be positive");
  ValidateAerosol(AerosolSettings{settings.aerosol_type, 0.1, std::numeric_limits<double>::quiet_NaN()});

  const SpectralConversion convert(base.wavelengths_nm);
  const double tol = settings.tolerance;
  const double m_direct = measured.direct_normal_lux;
  const double m_diffuse = measured.diffuse_horizontal_lux;
  const std::string& type = settings.aerosol_type;
  const DirectLight direct(base, type, altitude_m, s, settings.sun_scale);
  const auto quadrature_direct = [&](double aod) { return direct.Lux(aod); };

  CalibrationResult result;
  // The sky sampled by Tregenza patches, 3 x 3 each (within 0.5 % of the fine grid,
  // tests/irradiance_test.cc), each direction marched.
  const SkyPatches patches = SkyPatches::Reinhart(1);
  IrradianceSettings irradiance;
  irradiance.patches = &patches;
  irradiance.patch_samples = 3;
  irradiance.circumsolar_subdivisions = 8;
  irradiance.circumsolar_half_angle_deg = settings.circumsolar_half_angle_deg;
  irradiance.sun_scale = settings.sun_scale;
  const Plane planes[] = {Plane::Horizontal(), Plane::FacingSun()};
  double aod = 0.0;
  // One model per (aod, albedo): a full precomputation.
  const auto evaluate = [&](double albedo) {
    const AtmosphereParameters p = WithAerosol(base, type, aod, albedo);
    const std::unique_ptr<Model> model = CreateModel(settings.model, p, DaylightModelOptions(settings.model, settings.options));
    ++result.model_builds;
    const std::unique_ptr<SkyView> view = model->View(altitude_m, s);
    const IrradianceResult e = ComputeIrradiance(*view, p, planes, irradiance);
    Evaluation out;
    out.albedo = albedo;
    out.diffuse_lux = convert.Luminance(e.planes[0].sky_diffuse);
    out.circumsolar_lux = convert.Luminance(e.planes[1].circumsolar);
    out.direct_lux = convert.Luminance(e.direct_normal);
    return out;
  };
  const auto finish = [&](CalibrationStatus status, double albedo, const Evaluation* e, std::string message) {
    result.status = status;
    result.aod_550 = aod;
    result.parameters = WithAerosol(base, type, aod, albedo);
    result.single_scattering_albedo_550 = MieSingleScatteringAlbedo550(result.parameters);
    if (e != nullptr) {
      result.direct_normal_lux = e->direct_lux + e->circumsolar_lux;
      result.diffuse_horizontal_lux = e->diffuse_lux;
    }
    result.message = std::move(message);
    return result;
  };

  double circumsolar = 0.0;  // lux, from the last model
  double model_over_quadrature = 1.0;
  double albedo = MieSingleScatteringAlbedo550(WithAerosol(base, type, 0.1, std::numeric_limits<double>::quiet_NaN()));
  albedo = std::clamp(albedo, lo_albedo, hi_albedo);
  std::optional<Evaluation> last;
  for (int round = 0; round < 4; ++round) {
    // The optical depth whose disc light, with the last model's aureole, is the measured direct light.
    const double target = (m_direct - circumsolar) / model_over_quadrature;
    const double clearest = quadrature_direct(0.0);
    if (target > clearest * (1.0 + tol)) {
      aod = 0.0;
      return finish(CalibrationStatus::kTooMuchDirect, albedo, last ? &*last : nullptr,
                    "the direct normal " + Lux(m_direct) + " is more than the " + Lux(clearest * model_over_quadrature + circumsolar) +
                        " that this air transmits without any aerosol: check the measurement or the station's altitude");
    }
    if (target <= quadrature_direct(kMaxAerosolOpticalDepth)) {
      aod = kMaxAerosolOpticalDepth;
      return finish(CalibrationStatus::kTooLittleDirect, albedo, last ? &*last : nullptr,
                    "the direct normal " + Lux(m_direct) + " is less than an aerosol optical depth of 10 transmits: "
                    "not a clear sky (clouds or fog)");
    }
    aod = direct.OpticalDepthFor(target);

    // The albedo whose diffuse light is the measured one: regula falsi (Illinois) on a bracket.
    const auto close = [&](const Evaluation& e) { return std::abs(e.diffuse_lux - m_diffuse) <= tol * m_diffuse; };
    Evaluation a = evaluate(albedo);
    Evaluation found = a;
    if (!close(a)) {
      const bool need_more = a.diffuse_lux < m_diffuse;
      const double end = need_more ? hi_albedo : lo_albedo;
      Evaluation b = a.albedo == end ? a : evaluate(end);
      if (close(b)) {
        found = b;
      } else if ((b.diffuse_lux < m_diffuse) == need_more) {
        // The end of the range does not reach the measurement.
        if (need_more) {
          return finish(CalibrationStatus::kTooMuchDiffuse, end, &b,
                        "the diffuse horizontal " + Lux(m_diffuse) + " is " + Fixed(m_diffuse / b.diffuse_lux, 2) +
                            "x the " + Lux(b.diffuse_lux) + " of the most scattering aerosol (omega_550 " +
                            Fixed(end, 2) + ") at the optical depth " + Fixed(aod, 3) +
                            " that the direct light fixes: not a clear sky (clouds?)");
        }
        return finish(CalibrationStatus::kTooLittleDiffuse, end, &b,
                      "the diffuse horizontal " + Lux(m_diffuse) + " is less than the " + Lux(b.diffuse_lux) +
                          " of the most absorbing aerosol of the range (omega_550 " + Fixed(end, 2) +
                          ") at the optical depth " + Fixed(aod, 3) + ": check the measurement or the ground's albedo");
      } else {
        double fa = a.diffuse_lux - m_diffuse, fb = b.diffuse_lux - m_diffuse;
        int side = 0;
        found = b;
        while (!close(found)) {
          if (result.model_builds >= settings.max_model_builds) {
            last = found;
            return finish(CalibrationStatus::kNotConverged, found.albedo, &found,
                          "no albedo within " + Fixed(100.0 * tol, 1) + " % after " +
                              std::to_string(result.model_builds) + " models");
          }
          const double x = (a.albedo * fb - b.albedo * fa) / (fb - fa);
          const Evaluation c = evaluate(x);
          const double fc = c.diffuse_lux - m_diffuse;
          found = c;
          if ((fc < 0.0) == (fa < 0.0)) {
            a = c;
            fa = fc;
            if (side == -1) fb *= 0.5;
            side = -1;
          } else {
            b = c;
            fb = fc;
            if (side == 1) fa *= 0.5;
            side = 1;
          }
        }
      }
    }
    albedo = found.albedo;
    last = found;
    // The aureole the pyrheliometer adds, and the model's own transmittance against the quadrature's.
    const double new_circumsolar = found.circumsolar_lux;
    const double quadrature = quadrature_direct(aod);
    const double new_ratio = quadrature > 0.0 ? found.direct_lux / quadrature : 1.0;
    const double model_direct = found.direct_lux + found.circumsolar_lux;
    if (std::abs(model_direct - m_direct) <= tol * m_direct) {
      return finish(CalibrationStatus::kClear, albedo, &found,
                    "aod_550 " + Fixed(aod, 4) + ", omega_550 " + Fixed(MieSingleScatteringAlbedo550(WithAerosol(base, type, aod, albedo)), 4) +
                        " (" + type + "): direct normal " + Lux(model_direct) + " (measured " + Lux(m_direct) +
                        "), diffuse horizontal " + Lux(found.diffuse_lux) + " (measured " + Lux(m_diffuse) + ")");
    }
    circumsolar = new_circumsolar;
    model_over_quadrature = new_ratio;
    if (result.model_builds >= settings.max_model_builds) break;
  }
  return finish(CalibrationStatus::kNotConverged, albedo, last ? &*last : nullptr,
                "the direct and diffuse light did not agree together within " + Fixed(100.0 * tol, 1) + " % after " +
                    std::to_string(result.model_builds) + " models");
}

}  // namespace atmo
