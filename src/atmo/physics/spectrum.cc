// Spectral tables, Rayleigh scattering from first principles, and spectral atmospheres
// (include/atmo/spectrum.h).
#include "atmo/spectrum.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <numbers>
#include <string>

#include "atmo/error.h"
#include "physics/gases.h"
#include "printable.h"
#include "physics/data/scotopic_table.h"
#include "physics/data/spectral_tables.h"

namespace atmo {
namespace {

// Linear interpolation in a table of `count` values at first + k * step, held at the end values.
template <typename Get>
double InterpolateTable(double x, double first, double step, int count, const Get& get) {
  const double u = (x - first) / step;
  if (!(u > 0.0)) return get(0);
  if (u >= count - 1) return get(count - 1);
  const int k = static_cast<int>(u);
  const double f = u - k;
  return get(k) * (1.0 - f) + get(k + 1) * f;
}

// The 10 nm bin tables: entry k is the mean over [360 + 10 k, 370 + 10 k), placed at its centre.
double InterpolateBins(double wavelength_nm, const double (&table)[data::kSolarBinCount]) {
  return InterpolateTable(wavelength_nm, data::kSolarBinFirstNm + 0.5 * data::kSolarBinWidthNm,
                          data::kSolarBinWidthNm, data::kSolarBinCount, [&](int k) { return table[k]; });
}

void CheckWavelength(double wavelength_nm) {
  if (!std::isfinite(wavelength_nm) || wavelength_nm <= 0.0) {
    throw Error("wavelength " + std::to_string(wavelength_nm) + " nm must be finite and positive");
  }
}

// Least-squares fit of log(values) = log(k) + log(shape(lambda)): k = exp(mean(log(value/shape)))
// over the channels with a positive value (0 when there is none).
template <typename Shape>
double FitScale(const std::vector<double>& wavelengths, const std::vector<double>& values, const Shape& shape) {
  double sum = 0.0;
  int n = 0;
  for (std::size_t i = 0; i < values.size(); ++i) {
    if (values[i] > 0.0) {
      sum += std::log(values[i] / shape(wavelengths[i]));
      ++n;
    }
  }
  return n == 0 ? 0.0 : std::exp(sum / n);
}

// An Angstrom law a * (lambda / 550)^-alpha fitted in log-log space to the positive values; a
// single positive value (or equal wavelengths) gives alpha = 0.
struct AngstromLaw {
  double at_550 = 0.0;
  double alpha = 0.0;
  double operator()(double wavelength_nm) const { return at_550 * std::pow(wavelength_nm / 550.0, -alpha); }
};

AngstromLaw FitAngstrom(const std::vector<double>& wavelengths, const std::vector<double>& values) {
  double sx = 0.0, sy = 0.0, sxx = 0.0, sxy = 0.0;
  int n = 0;
  for (std::size_t i = 0; i < values.size(); ++i) {
    if (!(values[i] > 0.0)) continue;
    const double x = std::log(wavelengths[i] / 550.0);
    const double y = std::log(values[i]);
    sx += x;
    sy += y;
    sxx += x * x;
    sxy += x * y;
    ++n;
  }
  AngstromLaw law;
  if (n == 0) return law;
  const double denominator = n * sxx - sx * sx;
  const double slope = std::abs(denominator) > 1e-12 * std::max(1.0, n * sxx) ? (n * sxy - sx * sy) / denominator : 0.0;
  law.alpha = -slope;
  law.at_550 = std::exp((sy - slope * sx) / n);
  return law;
}

// Piecewise-linear interpolation in wavelength between (unsorted) channels, held beyond them.
double InterpolateChannels(const std::vector<double>& wavelengths, const std::vector<double>& values, double x) {
  std::vector<std::size_t> order(wavelengths.size());
  for (std::size_t i = 0; i < order.size(); ++i) order[i] = i;
  std::sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) { return wavelengths[a] < wavelengths[b]; });
  if (x <= wavelengths[order.front()]) return values[order.front()];
  if (x >= wavelengths[order.back()]) return values[order.back()];
  for (std::size_t k = 0; k + 1 < order.size(); ++k) {
    const double x0 = wavelengths[order[k]];
    const double x1 = wavelengths[order[k + 1]];
    if (x <= x1) {
      const double f = x1 > x0 ? (x - x0) / (x1 - x0) : 0.0;
      return values[order[k]] * (1.0 - f) + values[order[k + 1]] * f;
    }
  }
  return values[order.back()];
}

// The tent 0 at 10 km, 1 at 25 km, 0 at 40 km integrates to 15 km: a column of C molecules per m^2
// has C / 15 km molecules per m^3 at the peak.
constexpr double kOzoneTentIntegralM = 15e3;

}  // namespace

glm::dvec3 CieColourMatching(double wavelength_nm) {
  if (!(wavelength_nm >= kSpectrumMinNm && wavelength_nm <= kSpectrumMaxNm)) return glm::dvec3(0.0);
  glm::dvec3 v;
  for (int c = 0; c < 3; ++c) {
    v[c] = InterpolateTable(wavelength_nm, data::kCieFirstNm, data::kCieStepNm, data::kCieCount,
                            [&](int k) { return data::kCie1931[k][c]; });
  }
  return v;
}

double ScotopicEfficiency(double wavelength_nm) {
  const double x = (wavelength_nm - data::kScotopicFirstNm) / data::kScotopicStepNm;
  if (!(x >= 0.0) || x > data::kScotopicCount - 1) return 0.0;
  const int i = std::min(static_cast<int>(x), data::kScotopicCount - 2);
  const double f = x - i;
  return (1.0 - f) * data::kScotopicEfficiency[i] + f * data::kScotopicEfficiency[i + 1];
}

double SolarSpectralIrradiance(double wavelength_nm) {
  return InterpolateBins(wavelength_nm, data::kSolarIrradianceAstmG173);
}

double OzoneCrossSection(double wavelength_nm) { return InterpolateBins(wavelength_nm, data::kOzoneCrossSection233K); }

// Bodhaine et al. 1999, "On Rayleigh optical depth calculations", J. Atmos. Ocean. Tech. 16:
//   (n_300 - 1) 1e8 = 8060.51 + 2480990 / (132.274 - l^-2) + 17455.7 / (39.32957 - l^-2)   (l in um;
//     Peck & Reeder 1972, standard air with 300 ppm CO2, their eq. 4),
//   (n - 1) = (n_300 - 1) (1 + 0.54 (C - 0.0003))            (C: CO2 in parts per volume, eq. 19),
//   F(N2) = 1.034 + 3.17e-4 l^-2, F(O2) = 1.096 + 1.385e-3 l^-2 + 1.448e-4 l^-4, F(Ar) = 1,
//   F(CO2) = 1.15, F(air) their mean weighted by 78.084, 20.946, 0.934 and 100 C per cent (eq. 23),
//   sigma = 24 pi^3 (n^2 - 1)^2 / (lambda^4 N_s^2 (n^2 + 2)^2) F(air)            (eq. 2),
// with N_s the number density at which n was measured (288.15 K, 1013.25 hPa).
double RayleighCrossSection(double wavelength_nm, double co2_ppm) {
  CheckWavelength(wavelength_nm);
  if (!std::isfinite(co2_ppm) || co2_ppm < 0.0 || co2_ppm > 1e5) {
    throw Error("co2_ppm " + std::to_string(co2_ppm) + " is outside [0, 100000]");
  }
  const double l_um = wavelength_nm * 1e-3;
  const double inv_l2 = 1.0 / (l_um * l_um);
  const double n300_minus_1 = (8060.51 + 2480990.0 / (132.274 - inv_l2) + 17455.7 / (39.32957 - inv_l2)) * 1e-8;
  const double c = co2_ppm * 1e-6;
  const double n_minus_1 = n300_minus_1 * (1.0 + 0.54 * (c - 0.0003));
  const double n2 = (1.0 + n_minus_1) * (1.0 + n_minus_1);
  const double f_n2 = 1.034 + 3.17e-4 * inv_l2;
  const double f_o2 = 1.096 + 1.385e-3 * inv_l2 + 1.448e-4 * inv_l2 * inv_l2;
  const double c_percent = 100.0 * c;
  const double king = (78.084 * f_n2 + 20.946 * f_o2 + 0.934 * 1.0 + c_percent * 1.15) /
                      (78.084 + 20.946 + 0.934 + c_percent);
  const double lambda_m = wavelength_nm * 1e-9;
  const double pi3 = std::numbers::pi * std::numbers::pi * std::numbers::pi;
  const double ns = kAirNumberDensityAtSeaLevel;
  const double ratio = (n2 - 1.0) / (n2 + 2.0);
  return 24.0 * pi3 * ratio * ratio / (lambda_m * lambda_m * lambda_m * lambda_m * ns * ns) * king;
}

std::vector<double> SpectralWavelengths(int count) {
  if (count < 2) throw Error("a spectral atmosphere needs at least 2 wavelengths (got " + std::to_string(count) + ")");
  std::vector<double> wavelengths(static_cast<std::size_t>(count));
  for (int i = 0; i < count; ++i) {
    wavelengths[static_cast<std::size_t>(i)] = kSpectrumMinNm + (kSpectrumMaxNm - kSpectrumMinNm) * i / (count - 1);
  }
  return wavelengths;
}

AtmosphereParameters EarthSpectral(const SpectralEarthSettings& s) {
  const auto check = [](double value, double min, double max, const char* key) {
    if (!std::isfinite(value) || value < min || value > max) {
      throw Error(std::string(key) + " = " + std::to_string(value) + " is outside [" + std::to_string(min) + ", " +
                  std::to_string(max) + "]");
    }
  };
  check(s.wavelength_count, 3, 256, "wavelength_count");
  check(s.ozone_column_du, 0.0, 1e4, "ozone_column_du");
  check(s.aerosol_optical_depth_550, 0.0, 100.0, "aerosol_optical_depth_550");
  check(s.angstrom_exponent, -4.0, 4.0, "angstrom_exponent");
  check(s.aerosol_single_scattering_albedo, 0.0, 1.0, "aerosol_single_scattering_albedo");
  check(s.ground_albedo, 0.0, 1.0, "ground_albedo");

  AtmosphereParameters p = Preset("earth");
  p.name = "earth-spectral";
  p.wavelengths_nm = SpectralWavelengths(s.wavelength_count);
  const std::size_t n = p.wavelengths_nm.size();
  const double mie_scale_height_m = 1200.0;
  const double ozone_peak_per_m3 = s.ozone_column_du * kDobsonUnitPerM2 / kOzoneTentIntegralM;
  for (Medium* medium : {&p.rayleigh, &p.mie, &p.ozone}) {
    medium->scattering_per_m.assign(n, 0.0);
    medium->absorption_per_m.assign(n, 0.0);
  }
  p.ground_albedo.assign(n, s.ground_albedo);
  p.solar_irradiance.assign(n, 0.0);
  for (std::size_t i = 0; i < n; ++i) {
    const double lambda = p.wavelengths_nm[i];
    p.rayleigh.scattering_per_m[i] = RayleighCrossSection(lambda, s.co2_ppm) * kAirNumberDensityAtSeaLevel;
    const double mie_extinction =
        s.aerosol_optical_depth_550 / mie_scale_height_m * std::pow(lambda / 550.0, -s.angstrom_exponent);
    p.mie.scattering_per_m[i] = mie_extinction * s.aerosol_single_scattering_albedo;
    p.mie.absorption_per_m[i] = mie_extinction - p.mie.scattering_per_m[i];
    p.ozone.absorption_per_m[i] = OzoneCrossSection(lambda) * ozone_peak_per_m3;
    p.solar_irradiance[i] = SolarSpectralIrradiance(lambda);
  }
  Validate(p);
  return p;
}

AtmosphereParameters MakeSpectral(const AtmosphereParameters& in, int count) {
  if (count < 3 || count > 256) {
    throw Error("--spectral " + std::to_string(count) + ": the wavelength count must be in [3, 256]");
  }
  return MakeSpectral(in, SpectralWavelengths(count));
}

AtmosphereParameters MakeSpectral(const AtmosphereParameters& in, std::span<const double> wavelengths_nm) {
  if (wavelengths_nm.empty() || wavelengths_nm.size() > 256) {
    throw Error("--wavelengths: between 1 and 256 wavelengths are needed (got " +
                std::to_string(wavelengths_nm.size()) + ")");
  }
  for (std::size_t i = 0; i < wavelengths_nm.size(); ++i) {
    const double w = wavelengths_nm[i];
    if (!(w >= kSpectrumMinNm && w <= kSpectrumMaxNm)) {
      throw Error("--wavelengths: " + FormatNumber(w) + " nm is outside [" + FormatNumber(kSpectrumMinNm) + ", " +
                  FormatNumber(kSpectrumMaxNm) + "] nm, the range of atmo's spectral data");
    }
    if (i > 0 && !(w > wavelengths_nm[i - 1])) {
      throw Error("--wavelengths must increase (" + FormatNumber(wavelengths_nm[i - 1]) + " nm, then " +
                  FormatNumber(w) + " nm)");
    }
  }
  Validate(in);
  AtmosphereParameters p = in;
  p.wavelengths_nm.assign(wavelengths_nm.begin(), wavelengths_nm.end());
  const std::vector<double>& from = in.wavelengths_nm;
  const std::vector<double>& to = p.wavelengths_nm;
  const std::size_t n = to.size();
  const bool physical = in.geometry == Geometry::kSpherical;
  const auto rayleigh_shape = [](double lambda) { return RayleighCrossSection(lambda); };

  const auto resample = [&](const Medium& source, Medium& target, bool rayleigh_like, bool ozone_like) {
    std::vector<double> extinction(from.size());
    std::vector<double> albedo(from.size());
    for (std::size_t i = 0; i < from.size(); ++i) {
      extinction[i] = source.extinction_per_m(i);
      albedo[i] = extinction[i] > 0.0 ? source.scattering_per_m[i] / extinction[i] : 0.0;
    }
    target.scattering_per_m.assign(n, 0.0);
    target.absorption_per_m.assign(n, 0.0);
    // A medium with a known spectral shape: both coefficients scaled to fit the given values.
    const auto scale_shape = [&](const auto& shape) {
      const double k_s = FitScale(from, source.scattering_per_m, shape);
      const double k_a = FitScale(from, source.absorption_per_m, shape);
      for (std::size_t i = 0; i < n; ++i) {
        target.scattering_per_m[i] = k_s * shape(to[i]);
        target.absorption_per_m[i] = k_a * shape(to[i]);
      }
    };
    if (physical && rayleigh_like) return scale_shape(rayleigh_shape);
    if (physical && ozone_like) return scale_shape(OzoneCrossSection);
    const AngstromLaw law = FitAngstrom(from, extinction);
    for (std::size_t i = 0; i < n; ++i) {
      const double e = law(to[i]);
      const double a = std::clamp(InterpolateChannels(from, albedo, to[i]), 0.0, 1.0);
      target.scattering_per_m[i] = e * a;
      target.absorption_per_m[i] = e - e * a;
    }
  };
  resample(in.rayleigh, p.rayleigh, /*rayleigh_like=*/true, false);
  resample(in.mie, p.mie, false, false);
  resample(in.ozone, p.ozone, false, /*ozone_like=*/true);
  // The gases' bands are narrower than the channels: recomputed for the new channels' bands from
  // the amounts the old channels imply (include/atmo/gas_absorption.h), not interpolated.
  const bool gases = physical && (in.water_vapor.present() ||
                                  std::any_of(in.rayleigh.absorption_per_m.begin(),
                                              in.rayleigh.absorption_per_m.end(), [](double a) { return a > 0.0; }));
  if (gases) {
    const GasAmounts amounts = InferGasAmounts(in);
    SetGasAbsorption(p, amounts.ground_air_per_m3, amounts.water_peak_per_m3);
  } else if (!in.water_vapor.absorption_per_m.empty()) {
    resample(in.water_vapor, p.water_vapor, false, false);
  }
  p.ground_albedo.assign(n, 0.0);
  p.solar_irradiance.assign(n, 0.0);
  for (std::size_t i = 0; i < n; ++i) {
    p.ground_albedo[i] = std::clamp(InterpolateChannels(from, in.ground_albedo, to[i]), 0.0, 1.0);
    p.solar_irradiance[i] = SolarSpectralIrradiance(to[i]);
  }
  Validate(p);
  return p;
}

}  // namespace atmo
