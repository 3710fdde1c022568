// Spectral radiance to XYZ, luminance and linear sRGB; CIELAB and CIEDE2000 (include/atmo/colour.h).
#include "atmo/colour.h"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <numeric>
#include <string>

#include "atmo/error.h"
#include "atmo/spectrum.h"

namespace atmo {
namespace {

// IEC 61966-2-1 (sRGB), XYZ -> linear RGB for the Rec.709 primaries and the D65 white. glm is
// column-major: each glm::dvec3 below is a column of the matrix.
const glm::dmat3 kXyzToSrgb(glm::dvec3(3.2406, -0.9689, 0.0557), glm::dvec3(-1.5372, 1.8758, -0.2040),
                            glm::dvec3(-0.4986, 0.0415, 1.0570));

// The hat function of channel `k` among wavelengths sorted as `order`, held at 1 beyond the first
// and last channel: the weight of r_k in the piecewise-linear spectrum at `lambda`.
double ChannelWeight(const std::vector<double>& sorted, std::size_t k, double lambda) {
  const std::size_t n = sorted.size();
  if (n == 1) return 1.0;
  if (lambda <= sorted.front()) return k == 0 ? 1.0 : 0.0;
  if (lambda >= sorted.back()) return k == n - 1 ? 1.0 : 0.0;
  if (k > 0 && lambda >= sorted[k - 1] && lambda <= sorted[k]) {
    return sorted[k] > sorted[k - 1] ? (lambda - sorted[k - 1]) / (sorted[k] - sorted[k - 1]) : 1.0;
  }
  if (k + 1 < n && lambda >= sorted[k] && lambda < sorted[k + 1]) {
    return (sorted[k + 1] - lambda) / (sorted[k + 1] - sorted[k]);
  }
  return 0.0;
}

}  // namespace

std::size_t SampleChannels(RadianceUnit unit, std::size_t channels) {
  return unit == RadianceUnit::kLuminance ? 1 : channels;
}

void ConvertSample(const SpectralConversion& convert, RadianceUnit unit, std::span<const double> radiance,
                   std::span<const double> transmittance, std::span<const double> standard_error,
                   std::span<double> out_radiance, std::span<double> out_transmittance, std::span<double> out_error) {
  const std::size_t nc = convert.channel_count();
  if (unit == RadianceUnit::kLuminance) {
    double weight_sum = 0.0, luminous_transmittance = 0.0, variance = 0.0;
    for (std::size_t c = 0; c < nc; ++c) {
      const double w = kMaxLuminousEfficacy * convert.xyz_weights()[c].y;
      weight_sum += w;
      luminous_transmittance += w * transmittance[c];
      variance += (w * standard_error[c]) * (w * standard_error[c]);
    }
    out_radiance[0] = convert.Luminance(radiance);
    out_transmittance[0] = weight_sum > 0.0 ? luminous_transmittance / weight_sum : 0.0;
    out_error[0] = std::sqrt(variance);
    return;
  }
  for (std::size_t c = 0; c < nc; ++c) {
    const double scale = unit == RadianceUnit::kRadiance ? convert.solar_irradiance()[c] : 1.0;
    out_radiance[c] = scale * radiance[c];
    out_transmittance[c] = transmittance[c];
    out_error[c] = scale * standard_error[c];
  }
}

RadianceUnit ParseRadianceUnit(std::string_view name) {
  if (name == "relative") return RadianceUnit::kRelative;
  if (name == "radiance") return RadianceUnit::kRadiance;
  if (name == "luminance") return RadianceUnit::kLuminance;
  throw Error("unknown unit '" + std::string(name) + "' (use relative, radiance or luminance)");
}

std::string_view ToString(RadianceUnit unit) {
  switch (unit) {
    case RadianceUnit::kRelative: return "relative";
    case RadianceUnit::kRadiance: return "radiance";
    case RadianceUnit::kLuminance: return "luminance";
  }
  return "relative";
}

std::string_view UnitSymbol(RadianceUnit unit) {
  switch (unit) {
    case RadianceUnit::kRelative: return "sr^-1 per unit solar irradiance";
    case RadianceUnit::kRadiance: return "W m^-2 sr^-1 nm^-1";
    case RadianceUnit::kLuminance: return "cd/m^2";
  }
  return "";
}

// w_k = integral over [360, 830] nm of cmf(lambda) E(lambda) h_k(lambda) d(lambda), by the
// trapezoid rule at 1 nm (the tables are at 5 and 10 nm, linear in between, so 1 nm resolves
// them; the hats add kinks at the channel wavelengths, whose error shrinks as 1 nm^2).
SpectralConversion::SpectralConversion(std::span<const double> wavelengths_nm)
    : wavelengths_nm_(wavelengths_nm.begin(), wavelengths_nm.end()) {
  if (wavelengths_nm_.empty()) throw Error("a colour conversion needs at least one wavelength");
  for (double w : wavelengths_nm_) {
    if (!std::isfinite(w) || w <= 0.0) throw Error("wavelength " + std::to_string(w) + " nm must be positive");
  }
  const std::size_t n = wavelengths_nm_.size();
  std::vector<std::size_t> order(n);
  std::iota(order.begin(), order.end(), std::size_t{0});
  std::stable_sort(order.begin(), order.end(),
                   [&](std::size_t a, std::size_t b) { return wavelengths_nm_[a] < wavelengths_nm_[b]; });
  std::vector<double> sorted(n);
  for (std::size_t k = 0; k < n; ++k) sorted[k] = wavelengths_nm_[order[k]];

  xyz_weights_.assign(n, glm::dvec3(0.0));
  radiance_weights_.assign(n, 0.0);
  scotopic_weights_.assign(n, 0.0);
  solar_irradiance_.resize(n);
  for (std::size_t i = 0; i < n; ++i) solar_irradiance_[i] = SolarSpectralIrradiance(wavelengths_nm_[i]);
  const int steps = static_cast<int>(kSpectrumMaxNm - kSpectrumMinNm);
  for (int s = 0; s <= steps; ++s) {
    const double lambda = kSpectrumMinNm + s;
    const double dl = (s == 0 || s == steps) ? 0.5 : 1.0;
    const double e = SolarSpectralIrradiance(lambda) * dl;
    const glm::dvec3 cmf = CieColourMatching(lambda);
    const double scotopic = ScotopicEfficiency(lambda);
    for (std::size_t k = 0; k < n; ++k) {
      const double h = ChannelWeight(sorted, k, lambda);
      if (h == 0.0) continue;
      xyz_weights_[order[k]] += cmf * (e * h);
      radiance_weights_[order[k]] += e * h;
      scotopic_weights_[order[k]] += kMaxScotopicEfficacy * scotopic * e * h;
    }
  }
}

glm::dvec3 SpectralConversion::Xyz(std::span<const double> relative) const {
  glm::dvec3 xyz(0.0);
  for (std::size_t i = 0; i < xyz_weights_.size(); ++i) xyz += xyz_weights_[i] * relative[i];
  return xyz;
}

double SpectralConversion::ScotopicLuminance(std::span<const double> relative) const {
  double sum = 0.0;
  for (std::size_t i = 0; i < scotopic_weights_.size(); ++i) sum += scotopic_weights_[i] * relative[i];
  return sum;
}

double SpectralConversion::Luminance(std::span<const double> relative) const {
  return kMaxLuminousEfficacy * Xyz(relative).y;
}

double SpectralConversion::Radiance(std::span<const double> relative) const {
  double sum = 0.0;
  for (std::size_t i = 0; i < radiance_weights_.size(); ++i) sum += radiance_weights_[i] * relative[i];
  return sum;
}

glm::dvec3 SpectralConversion::LinearSrgb(std::span<const double> relative) const {
  return XyzToLinearSrgb(kMaxLuminousEfficacy * Xyz(relative));
}

double SpectralConversion::SpectralRadiance(std::size_t channel, double relative) const {
  return relative * solar_irradiance_[channel];
}

glm::dvec3 XyzToLinearSrgb(const glm::dvec3& xyz) { return kXyzToSrgb * xyz; }

namespace {

// The columns are the XYZ of R = 1, G = 1 and B = 1, scaled so that R = G = B = 1 is the
// equal-energy white X = Y = Z = 1 (then times the white efficacy).
glm::dmat3 RadianceRgbToXyzMatrix() {
  const double xy[3][2] = {{0.640, 0.330}, {0.290, 0.600}, {0.150, 0.060}};
  glm::dmat3 primaries;
  for (int i = 0; i < 3; ++i) primaries[i] = glm::dvec3(xy[i][0] / xy[i][1], 1.0, (1.0 - xy[i][0] - xy[i][1]) / xy[i][1]);
  const glm::dvec3 scale = glm::inverse(primaries) * glm::dvec3(1.0);
  for (int i = 0; i < 3; ++i) primaries[i] *= scale[i] * kRadianceWhiteEfficacy;
  return primaries;
}

}  // namespace

glm::dvec3 RadianceRgbToXyz(const glm::dvec3& rgb) {
  static const glm::dmat3 m = RadianceRgbToXyzMatrix();
  return m * rgb;
}

glm::dvec3 XyzToRadianceRgb(const glm::dvec3& xyz_cd_m2) {
  static const glm::dmat3 m = glm::inverse(RadianceRgbToXyzMatrix());
  return m * xyz_cd_m2;
}

glm::dvec3 XyzToRadianceRgbInGamut(const glm::dvec3& xyz_cd_m2) {
  const glm::dvec3 rgb = XyzToRadianceRgb(xyz_cd_m2);
  const double lowest = std::min({rgb.x, rgb.y, rgb.z});
  if (lowest >= 0.0) return rgb;
  const double grey = xyz_cd_m2.y / kRadianceWhiteEfficacy;  // R = G = B = grey has this luminance
  if (!(grey > 0.0)) return glm::dvec3(0.0);
  return glm::max(grey + (grey / (grey - lowest)) * (rgb - grey), 0.0);
}
glm::dvec3 LinearSrgbToXyz(const glm::dvec3& rgb) { return glm::inverse(kXyzToSrgb) * rgb; }

std::vector<glm::vec3> ColourWeights(const SpectralConversion& convert, ImageColour colour) {
  if (colour == ImageColour::kSpectral) throw Error("spectral images have no colour weights");
  std::vector<glm::vec3> weights(convert.channel_count());
  for (std::size_t c = 0; c < weights.size(); ++c) {
    const glm::dvec3 xyz = kMaxLuminousEfficacy * convert.xyz_weights()[c];
    weights[c] = glm::vec3(colour == ImageColour::kLinearSrgb ? XyzToLinearSrgb(xyz) : xyz);
  }
  return weights;
}

namespace {

void NameChannels(Image& image, ImageColour colour) {
  if (colour == ImageColour::kXyz) {
    image.channel_names = {"X", "Y", "Z"};
    image.colour_space = ColourSpace::kCieXyz;
  } else {
    image.colour_space = ColourSpace::kLinearSrgb;
  }
}

}  // namespace

Image ConvertStandardError(const Image& standard_error, const SpectralConversion& convert, ImageColour colour) {
  const std::size_t n = convert.channel_count();
  if (static_cast<std::size_t>(standard_error.channels) != n) {
    throw Error("the image has " + std::to_string(standard_error.channels) + " channels, the colour conversion " +
                std::to_string(n));
  }
  if (colour == ImageColour::kSpectral) return ConvertImage(standard_error, convert, colour);
  const std::vector<glm::vec3> weights = ColourWeights(convert, colour);
  Image out(standard_error.width, standard_error.height, 3);
  const std::size_t pixels = static_cast<std::size_t>(standard_error.width) * standard_error.height;
  for (std::size_t p = 0; p < pixels; ++p) {
    glm::vec3 sum(0.0f);
    for (std::size_t c = 0; c < n; ++c) {
      const glm::vec3 term = weights[c] * standard_error.pixels[p * n + c];
      sum += term * term;
    }
    for (int k = 0; k < 3; ++k) out.pixels[p * 3 + k] = std::sqrt(sum[k]);
  }
  NameChannels(out, colour);
  return out;
}

Image ConvertImage(const Image& relative, const SpectralConversion& convert, ImageColour colour) {
  const std::size_t n = convert.channel_count();
  if (static_cast<std::size_t>(relative.channels) != n) {
    throw Error("the image has " + std::to_string(relative.channels) + " channels, the colour conversion " +
                std::to_string(n));
  }
  const std::size_t pixels = static_cast<std::size_t>(relative.width) * relative.height;
  if (colour == ImageColour::kSpectral) {
    Image out = relative;
    for (std::size_t p = 0; p < pixels; ++p) {
      for (std::size_t c = 0; c < n; ++c) {
        float& v = out.pixels[p * n + c];
        v = static_cast<float>(convert.SpectralRadiance(c, v));
      }
    }
    out.channel_names.clear();
    out.colour_space = ColourSpace::kUnspecified;
    return out;
  }
  Image out(relative.width, relative.height, 3);
  out.alpha = relative.alpha;
  // Single-precision weights per output channel, folded with the XYZ -> sRGB matrix when asked.
  const std::vector<glm::vec3> weights = ColourWeights(convert, colour);
  for (std::size_t p = 0; p < pixels; ++p) {
    glm::vec3 sum(0.0f);
    for (std::size_t c = 0; c < n; ++c) sum += weights[c] * relative.pixels[p * n + c];
    for (int k = 0; k < 3; ++k) out.pixels[p * 3 + k] = sum[k];
  }
  NameChannels(out, colour);
  return out;
}

glm::dvec3 XyzToLab(const glm::dvec3& xyz, const glm::dvec3& white) {
  constexpr double kDelta = 6.0 / 29.0;
  const auto f = [](double t) {
    return t > kDelta * kDelta * kDelta ? std::cbrt(t) : t / (3.0 * kDelta * kDelta) + 4.0 / 29.0;
  };
  const double fx = f(xyz.x / white.x);
  const double fy = f(xyz.y / white.y);
  const double fz = f(xyz.z / white.z);
  return {116.0 * fy - 16.0, 500.0 * (fx - fy), 200.0 * (fy - fz)};
}

// Sharma, Wu and Dalal 2005, "The CIEDE2000 color-difference formula: implementation notes,
// supplementary test data, and mathematical observations", eqs. 1-22 (angles in degrees).
double DeltaE2000(const glm::dvec3& lab_1, const glm::dvec3& lab_2) {
  constexpr double kPi = std::numbers::pi;
  const auto rad = [](double deg) { return deg * kPi / 180.0; };
  const auto deg = [](double r) { return r * 180.0 / kPi; };
  const double pow25_7 = 6103515625.0;  // 25^7
  const double c1 = std::hypot(lab_1.y, lab_1.z);
  const double c2 = std::hypot(lab_2.y, lab_2.z);
  const double c_mean7 = std::pow(0.5 * (c1 + c2), 7.0);
  const double g = 0.5 * (1.0 - std::sqrt(c_mean7 / (c_mean7 + pow25_7)));
  const double a1 = (1.0 + g) * lab_1.y;
  const double a2 = (1.0 + g) * lab_2.y;
  const double c1p = std::hypot(a1, lab_1.z);
  const double c2p = std::hypot(a2, lab_2.z);
  const auto hue = [&](double b, double a) {
    if (a == 0.0 && b == 0.0) return 0.0;
    const double h = deg(std::atan2(b, a));
    return h < 0.0 ? h + 360.0 : h;
  };
  const double h1p = hue(lab_1.z, a1);
  const double h2p = hue(lab_2.z, a2);
  const double dl = lab_2.x - lab_1.x;
  const double dc = c2p - c1p;
  double dh = 0.0;
  if (c1p * c2p != 0.0) {
    dh = h2p - h1p;
    if (dh > 180.0) dh -= 360.0;
    else if (dh < -180.0) dh += 360.0;
  }
  const double dH = 2.0 * std::sqrt(c1p * c2p) * std::sin(rad(dh) / 2.0);
  const double l_mean = 0.5 * (lab_1.x + lab_2.x);
  const double c_mean_p = 0.5 * (c1p + c2p);
  double h_mean = h1p + h2p;
  if (c1p * c2p != 0.0) {
    if (std::abs(h1p - h2p) <= 180.0) h_mean = 0.5 * (h1p + h2p);
    else if (h1p + h2p < 360.0) h_mean = 0.5 * (h1p + h2p + 360.0);
    else h_mean = 0.5 * (h1p + h2p - 360.0);
  }
  const double t = 1.0 - 0.17 * std::cos(rad(h_mean - 30.0)) + 0.24 * std::cos(rad(2.0 * h_mean)) +
                   0.32 * std::cos(rad(3.0 * h_mean + 6.0)) - 0.20 * std::cos(rad(4.0 * h_mean - 63.0));
  const double d_theta = 30.0 * std::exp(-std::pow((h_mean - 275.0) / 25.0, 2.0));
  const double c_mean_p7 = std::pow(c_mean_p, 7.0);
  const double r_c = 2.0 * std::sqrt(c_mean_p7 / (c_mean_p7 + pow25_7));
  const double l50 = (l_mean - 50.0) * (l_mean - 50.0);
  const double s_l = 1.0 + 0.015 * l50 / std::sqrt(20.0 + l50);
  const double s_c = 1.0 + 0.045 * c_mean_p;
  const double s_h = 1.0 + 0.015 * c_mean_p * t;
  const double r_t = -std::sin(rad(2.0 * d_theta)) * r_c;
  const double x = dl / s_l, y = dc / s_c, z = dH / s_h;
  return std::sqrt(x * x + y * y + z * z + r_t * y * z);
}

}  // namespace atmo
