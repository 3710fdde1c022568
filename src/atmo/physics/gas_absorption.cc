#include "atmo/gas_absorption.h"

#include <algorithm>
#include <cmath>
#include <string>

#include "atmo/error.h"
#include "physics/data/gas_absorption.h"
#include "printable.h"

namespace atmo {
namespace {

// The tables are per cm^2 (cm^5 for O4); amounts here are per m^2 (m^5).
constexpr double kCm2PerM2 = 1e4;
constexpr double kCm5PerM5 = 1e10;

// Mean transmittance of 1 nm bin k for a slant amount (per m^2, or m^5 for O4).
double BinTransmittance(Gas gas, int k, double slant_amount) {
  switch (gas) {
    case Gas::kOxygen:
    case Gas::kWaterVapor: {
      const auto& quantiles =
          gas == Gas::kOxygen ? data::kO2CrossSectionQuantiles[k] : data::kH2OCrossSectionQuantiles[k];
      const double amount_per_cm2 = slant_amount / kCm2PerM2;
      double sum = 0.0;
      for (float sigma : quantiles) sum += std::exp(-static_cast<double>(sigma) * amount_per_cm2);
      return sum / data::kGasQuantileCount;
    }
    case Gas::kOxygenCollisions:
      // Smooth across a bin: Beer's law with the bin mean.
      return std::exp(-data::kO4CrossSection[k] * (slant_amount / kCm5PerM5));
  }
  return 1.0;
}

// The band's mean of value(k) over the 1 nm bins, each weighted by its overlap with the band;
// `outside` stands for the part of the band beyond the tables (360-830 nm).
template <typename Value>
double BandMean(WavelengthBand band, double outside, const Value& value) {
  const double first = data::kGasFirstBinNm;
  const double lo = std::clamp(band.lower_nm, first, first + data::kGasBinCount);
  const double hi = std::clamp(band.upper_nm, first, first + data::kGasBinCount);
  double sum = outside * ((band.upper_nm - band.lower_nm) - (hi - lo));
  for (int k = static_cast<int>(std::floor(lo - first)); k < data::kGasBinCount && first + k < hi; ++k) {
    const double overlap = std::min(hi, first + k + 1.0) - std::max(lo, first + k);
    if (overlap > 0.0) sum += overlap * value(k);
  }
  return sum / (band.upper_nm - band.lower_nm);
}

// The band's mean cross-section (per m^2, or m^5 for O4): the line-by-line bin means (the
// quantiles are medians of sixteenths, whose mean is lower).
double BandMeanCrossSection(Gas gas, WavelengthBand band) {
  return BandMean(band, 0.0, [&](int k) {
    if (gas == Gas::kOxygenCollisions) return data::kO4CrossSection[k] / kCm5PerM5;
    return (gas == Gas::kOxygen ? data::kO2CrossSectionBinMean[k] : data::kH2OCrossSectionBinMean[k]) / kCm2PerM2;
  });
}

}  // namespace

std::vector<WavelengthBand> ChannelBands(std::span<const double> wavelengths_nm) {
  const std::size_t n = wavelengths_nm.size();
  for (std::size_t i = 0; i < n; ++i) {
    if (!(std::isfinite(wavelengths_nm[i]) && wavelengths_nm[i] > 0.0)) {
      throw Error("channel bands need positive wavelengths (got " + FormatNumber(wavelengths_nm[i]) + " nm)");
    }
    if (i > 0 && !(wavelengths_nm[i] > wavelengths_nm[i - 1])) {
      throw Error("channel bands need increasing wavelengths (" + FormatNumber(wavelengths_nm[i - 1]) + " nm, then " +
                  FormatNumber(wavelengths_nm[i]) + " nm)");
    }
  }
  std::vector<WavelengthBand> bands(n);
  if (n == 1) {
    bands[0] = {wavelengths_nm[0] - 5.0, wavelengths_nm[0] + 5.0};
    return bands;
  }
  for (std::size_t i = 0; i < n; ++i) {
    const double lower = i > 0 ? 0.5 * (wavelengths_nm[i - 1] + wavelengths_nm[i])
                               : wavelengths_nm[0] - 0.5 * (wavelengths_nm[1] - wavelengths_nm[0]);
    const double upper = i + 1 < n ? 0.5 * (wavelengths_nm[i] + wavelengths_nm[i + 1])
                                   : wavelengths_nm[i] + 0.5 * (wavelengths_nm[i] - wavelengths_nm[i - 1]);
    bands[i] = {std::max(lower, 0.0), upper};
  }
  return bands;
}

double GasBandTransmittance(Gas gas, WavelengthBand band, double amount, double air_mass) {
  if (!(std::isfinite(amount) && amount >= 0.0)) {
    throw Error("gas amount must be finite and >= 0 (got " + FormatNumber(amount) + ")");
  }
  if (!(std::isfinite(air_mass) && air_mass >= 0.0)) {
    throw Error("air mass must be finite and >= 0 (got " + FormatNumber(air_mass) + ")");
  }
  if (!(std::isfinite(band.lower_nm) && std::isfinite(band.upper_nm) && band.upper_nm > band.lower_nm)) {
    throw Error("a wavelength band needs lower < upper (got " + FormatNumber(band.lower_nm) + "-" + FormatNumber(band.upper_nm) +
                " nm)");
  }
  const double slant = amount * air_mass;
  // No absorption outside the tables: transmittance 1 there.
  return BandMean(band, 1.0, [&](int k) { return BinTransmittance(gas, k, slant); });
}

double GasEffectiveCrossSection(Gas gas, WavelengthBand band, double amount, double air_mass) {
  if (!(std::isfinite(air_mass) && air_mass > 0.0)) {
    throw Error("the reference air mass must be finite and > 0 (got " + FormatNumber(air_mass) + ")");
  }
  const double t = GasBandTransmittance(gas, band, amount, air_mass);
  const double slant = amount * air_mass;
  // Below an optical depth of ~1e-9 the logarithm loses its digits: the band-mean cross-section,
  // which is the limit of the Beer-equivalent one for a vanishing amount.
  if (t > 1.0 - 1e-9) return BandMeanCrossSection(gas, band);
  return -std::log(std::max(t, 1e-300)) / slant;
}

}  // namespace atmo
