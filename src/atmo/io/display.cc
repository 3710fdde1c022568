// Exposure and display: EV100, auto-exposure, tone curves on luminance or per channel, the sRGB
// transfer function (see include/atmo/image.h and docs/display.md).
//
// Contracts:
// - Every mapping's results are in [0, 1]. The luminance curves and the per-channel mode are
//   monotonic non-decreasing in the linear input and in the exposure, per channel; AgX is for grey
//   pixels and for a pixel's luminance (its outset matrix lets one channel of a saturated colour
//   fall as the others rise towards white, which is the point of it).
// - The luminance mode only ever scales a pixel's RGB by one factor, so the linear chromaticity
//   (hue and saturation) of the output is that of the input.
#include <algorithm>
#include <array>
#include <cmath>
#include <cstddef>
#include <limits>
#include <string>
#include <vector>

#include "atmo/error.h"
#include "atmo/image.h"

namespace atmo {
namespace {

// The tone curve T of an exposed value v >= 0, in [0, 1].
double ToneCurve(double v, ToneMapper op) {
  if (std::isnan(v) || v <= 0.0) return 0.0;
  double t = 0.0;
  switch (op) {
    case ToneMapper::kExponential:
      t = 1.0 - std::exp(-v);
      break;
    case ToneMapper::kAces:
      // Narkowicz 2015, "ACES Filmic Tone Mapping Curve": x(a x + b) / (x(c x + d) + e). It is
      // increasing for x >= 0 and reaches 1 near x = 7.24; for huge x the ratio is inf/inf, whose
      // limit 2.51/2.43 > 1 clamps to 1.
      t = (v * (2.51 * v + 0.03)) / (v * (2.43 * v + 0.59) + 0.14);
      if (std::isnan(t)) t = 1.0;
      break;
    case ToneMapper::kNone:
      t = v;
      break;
    case ToneMapper::kAgx: {
      const auto grey = AgxDisplay(v, v, v);
      t = std::pow(grey[1], 2.2);
      break;
    }
  }
  return std::clamp(t, 0.0, 1.0);
}

// AgX. The numbers are Troy Sobotka's AgX base transform (github.com/sobotka/AgX, the view
// transform Blender 4 ships): the inset matrix, the log2 encoding from -12.47393 to +4.02607 stops
// about scene grey 0.18 (16.5 stops), and the sigmoid of its LUT generator in the closed form given
// by github.com/bWFuanVzYWth/AgX (README): with x0 = 20/33 (where grey 0.18 encodes),
//   f(x) = 1/2 + 2 (x - x0) (1 + a |x - x0|^b)^c,
// a = 59.507875, b = 3, c = -1/3 below x0 and a = 69.86278913545539, b = 13/4, c = -4/13 above;
// f(0) = 0 and f(1) = 1 to 1e-4. The output is encoded for a display of gamma 2.2.
constexpr double kAgxMinEv = -12.473931188332413;
constexpr double kAgxMaxEv = 4.026068811667588;
// Rows: AgX inset channel = row . (R, G, B) of linear Rec.709. Each row sums to 1 (grey stays grey).
constexpr double kAgxInset[3][3] = {
    {0.8424010709504686, 0.07843650156180276, 0.0791624274877287},
    {0.04240107095046854, 0.8784365015618028, 0.0791624274877287},
    {0.04240107095046854, 0.07843650156180276, 0.8791624274877287},
};

double AgxSigmoid(double x) {
  constexpr double x0 = 20.0 / 33.0;
  const double d = x - x0;
  // The same powers as above, in cheaper operations (this runs three times a pixel): u^3 as
  // products, u^-1/3 as 1 / cbrt(u), d^3.25 as d^3 d^(1/4).
  const double f = d <= 0.0 ? 0.5 + 2.0 * d / std::cbrt(1.0 - 59.507875 * d * d * d)
                            : 0.5 + 2.0 * d * std::pow(1.0 + 69.86278913545539 * d * d * d * std::sqrt(std::sqrt(d)),
                                                       -4.0 / 13.0);
  return std::clamp(f, 0.0, 1.0);
}

// The outset: the inverse of kAgxInset, computed once (a 3x3 inverse by cofactors).
std::array<std::array<double, 3>, 3> AgxOutset() {
  const auto& m = kAgxInset;
  const double det = m[0][0] * (m[1][1] * m[2][2] - m[1][2] * m[2][1]) -
                     m[0][1] * (m[1][0] * m[2][2] - m[1][2] * m[2][0]) +
                     m[0][2] * (m[1][0] * m[2][1] - m[1][1] * m[2][0]);
  std::array<std::array<double, 3>, 3> inverse{};
  for (int i = 0; i < 3; ++i) {
    for (int j = 0; j < 3; ++j) {
      // inverse[i][j] = cofactor(j, i) / det
      const int r0 = (j + 1) % 3, r1 = (j + 2) % 3, c0 = (i + 1) % 3, c1 = (i + 2) % 3;
      inverse[i][j] = (m[r0][c0] * m[r1][c1] - m[r0][c1] * m[r1][c0]) / det;
    }
  }
  return inverse;
}

// A linear channel as ToneMapPixel reads it: NaN and negative values are 0, +inf the largest
// float (so that a pixel with one infinite channel keeps a finite, if extreme, chromaticity).
double CleanChannel(float x) {
  if (!(x > 0.0f)) return 0.0;
  return std::isinf(x) ? static_cast<double>(std::numeric_limits<float>::max()) : static_cast<double>(x);
}

// A smooth function on [0, 1] as a table of kTableSize + 1 values read with linear interpolation:
// the tone mapping of a 1280x720 PNG calls AgX's two curves 8 million times, and their powers were
// most of its cost. Both curves' second derivatives are small enough that the table is within
// 1e-7 of the curve (AgxTables test), far below a 16-bit code (1.5e-5).
class CurveTable {
 public:
  static constexpr int kTableSize = 4096;
  template <typename F>
  explicit CurveTable(F&& f) {
    for (int i = 0; i <= kTableSize; ++i) values_[i] = f(static_cast<double>(i) / kTableSize);
  }
  double operator()(double x) const {
    const double t = std::clamp(x, 0.0, 1.0) * kTableSize;
    const int i = std::min(static_cast<int>(t), kTableSize - 1);
    return values_[i] + (t - i) * (values_[i + 1] - values_[i]);
  }

 private:
  std::array<double, kTableSize + 1> values_{};
};

// mapping.transfer of AgX's output v, which is encoded for a 2.2 display: EncodeDisplay(v^2.2),
// with the sRGB power segment's two powers folded into one, (v^2.2)^(1/2.4) = v^(2.2/2.4).
double EncodeAgx(double v, const ToneMapping& mapping) {
  if (!(v > 0.0)) return 0.0;
  if (v >= 1.0) return 1.0;
  if (mapping.transfer == DisplayTransfer::kSrgb) {
    static const double toe = std::pow(0.0031308, 1.0 / 2.2);  // v where v^2.2 meets the sRGB toe
    return v <= toe ? 12.92 * std::pow(v, 2.2) : 1.055 * std::pow(v, 2.2 / 2.4) - 0.055;
  }
  return EncodeDisplay(std::pow(v, 2.2), mapping);
}

}  // namespace

std::array<double, 3> AgxDisplay(double r, double g, double b) {
  static const std::array<std::array<double, 3>, 3> outset = AgxOutset();
  const double rgb[3] = {r, g, b};
  double encoded[3];
  for (int i = 0; i < 3; ++i) {
    double inset = 0.0;
    for (int j = 0; j < 3; ++j) inset += kAgxInset[i][j] * (std::isnan(rgb[j]) ? 0.0 : std::max(rgb[j], 0.0));
    // log2 of 0 is -inf, which the clamp to the lower end takes care of; +inf clamps to the top.
    const double stops = std::clamp(std::log2(inset), kAgxMinEv, kAgxMaxEv);
    static const CurveTable sigmoid(AgxSigmoid);
    encoded[i] = sigmoid((stops - kAgxMinEv) / (kAgxMaxEv - kAgxMinEv));
  }
  std::array<double, 3> out{};
  for (int i = 0; i < 3; ++i) {
    const double v = outset[i][0] * encoded[0] + outset[i][1] * encoded[1] + outset[i][2] * encoded[2];
    out[i] = std::clamp(v, 0.0, 1.0);
  }
  return out;
}

double AdaptationKey(double average_luminance) {
  if (!(average_luminance >= 0.0)) return 0.01;  // NaN or negative
  if (std::isinf(average_luminance)) return 1.03;
  return std::max(0.01, 1.03 - 2.0 / (2.0 + std::log10(average_luminance + 1.0)));
}

double MeteringKey(double average_luminance) {
  constexpr double kDaylightSky = 7000.0;  // cd/m^2, a clear sky's log-average with the sun high
  return 0.18 * AdaptationKey(average_luminance) / AdaptationKey(kDaylightSky);
}

ToneMapping SeedToneMapping(ToneMapper op, double exposure, double gamma) {
  ToneMapping mapping;
  mapping.op = op;
  mapping.exposure = exposure;
  mapping.gamma = gamma;
  mapping.per_channel = true;
  mapping.transfer = DisplayTransfer::kGamma;
  mapping.dither = false;
  mapping.bit_depth = 8;
  return mapping;
}

double Luminance(double r, double g, double b) { return 0.2126 * r + 0.7152 * g + 0.0722 * b; }

// ---------------------------------------------------------------------------------------------
// Exposure.

double ExposureFromEv100(double ev100) { return 1.0 / (1.2 * std::exp2(ev100)); }

double Ev100FromExposure(double exposure) {
  if (!(exposure > 0.0)) return std::numeric_limits<double>::quiet_NaN();
  return std::log2(1.0 / (1.2 * exposure));
}

double AutoExposureEv100(const Image& image, Metering metering) {
  if (image.channels < 3) {
    throw Error("auto-exposure needs an image with at least 3 channels, got " + std::to_string(image.channels));
  }
  const std::size_t pixel_count =
      image.width > 0 && image.height > 0 ? static_cast<std::size_t>(image.width) * image.height : 0;
  if (pixel_count == 0 || image.pixels.size() != pixel_count * image.channels ||
      (!image.alpha.empty() && image.alpha.size() != pixel_count)) {
    throw Error("auto-exposure of an inconsistent image (" + std::to_string(image.width) + "x" +
                std::to_string(image.height) + "x" + std::to_string(image.channels) + ", " +
                std::to_string(image.pixels.size()) + " values)");
  }

  std::vector<double> log_luminance;
  log_luminance.reserve(pixel_count);
  for (std::size_t i = 0; i < pixel_count; ++i) {
    if (!image.alpha.empty() && !(image.alpha[i] > 0.0f)) continue;  // outside (NaN too)
    const float* p = image.pixels.data() + i * image.channels;
    const double y = Luminance(p[0], p[1], p[2]);
    if (std::isfinite(y) && y > 0.0) log_luminance.push_back(std::log2(y));
  }
  if (log_luminance.empty()) return 0.0;

  // Winsorised mean of log2 L: values below the 2nd or above the 98th percentile count as that
  // percentile. A sun disc of less than 2% of the pixels, 10^5 times the sky's luminance, would
  // otherwise add (its share) * 17 stops to the mean; clamped, it counts as the brightest sky.
  const std::size_t n = log_luminance.size();
  const std::size_t low_rank = static_cast<std::size_t>(std::floor(0.02 * static_cast<double>(n - 1)));
  const std::size_t high_rank = static_cast<std::size_t>(std::ceil(0.98 * static_cast<double>(n - 1)));
  std::nth_element(log_luminance.begin(), log_luminance.begin() + high_rank, log_luminance.end());
  const double high = log_luminance[high_rank];
  std::nth_element(log_luminance.begin(), log_luminance.begin() + low_rank, log_luminance.begin() + high_rank + 1);
  const double low = log_luminance[low_rank];
  double sum = 0.0;
  for (double l : log_luminance) sum += std::clamp(l, low, high);
  return MeteredEv100(sum / static_cast<double>(n), metering);
}

double MeteredEv100(double log2_average, Metering metering) {
  if (metering == Metering::kAdaptive) {
    // The average at the adapted key: exposure * L_avg = key, exposure = 1 / (1.2 * 2^EV100).
    return log2_average - std::log2(1.2 * MeteringKey(std::exp2(log2_average)));
  }
  // Reflected-light meter: EV100 = log2(L_avg S / K), S = 100, K = 12.5, so log2(L_avg) + 3.
  constexpr double kSensitivity = 100.0, kCalibration = 12.5;
  return log2_average + std::log2(kSensitivity / kCalibration);
}

// ---------------------------------------------------------------------------------------------
// Display encoding.

double SrgbEncode(double linear) {
  if (!(linear > 0.0)) return 0.0;
  if (linear >= 1.0) return 1.0;
  // IEC 61966-2-1: the linear toe meets the power segment at 0.0031308, where both give 0.0404499
  // (to 3e-8; the standard rounds the joint to these digits).
  return linear <= 0.0031308 ? 12.92 * linear : 1.055 * std::pow(linear, 1.0 / 2.4) - 0.055;
}

double SrgbDecode(double encoded) {
  if (!(encoded > 0.0)) return 0.0;
  if (encoded >= 1.0) return 1.0;
  return encoded <= 0.04045 ? encoded / 12.92 : std::pow((encoded + 0.055) / 1.055, 2.4);
}

double EncodeDisplay(double linear, const ToneMapping& mapping) {
  if (!(linear > 0.0)) return 0.0;
  linear = std::min(linear, 1.0);
  switch (mapping.transfer) {
    case DisplayTransfer::kSrgb:
      return SrgbEncode(linear);
    case DisplayTransfer::kGamma:
      return mapping.gamma != 1.0 ? std::pow(linear, 1.0 / mapping.gamma) : linear;
    case DisplayTransfer::kIdentity:
      break;
  }
  return linear;
}

// ---------------------------------------------------------------------------------------------
// Tone mapping.

float ToneMapValue(float linear, const ToneMapping& mapping) {
  // `!(linear > 0)` also catches NaN.
  if (!(linear > 0.0f)) return 0.0f;
  const double t = ToneCurve(mapping.exposure * static_cast<double>(linear), mapping.op);
  return static_cast<float>(EncodeDisplay(t, mapping));
}

std::array<float, 3> ToneMapPixel(float r, float g, float b, const ToneMapping& mapping) {
  if (mapping.op == ToneMapper::kAgx) {
    if (!(mapping.exposure > 0.0)) return {0.0f, 0.0f, 0.0f};
    const double e = mapping.exposure;
    if (!(CleanChannel(r) + CleanChannel(g) + CleanChannel(b) > 0.0)) return {0.0f, 0.0f, 0.0f};
    const auto display = AgxDisplay(e * CleanChannel(r), e * CleanChannel(g), e * CleanChannel(b));
    std::array<float, 3> out{};
    static const CurveTable srgb([](double v) { return EncodeAgx(v, ToneMapping{}); });
    for (int c = 0; c < 3; ++c) {
      out[c] = static_cast<float>(mapping.transfer == DisplayTransfer::kSrgb ? srgb(display[c])
                                                                             : EncodeAgx(display[c], mapping));
    }
    return out;
  }
  if (mapping.per_channel) {
    return {ToneMapValue(r, mapping), ToneMapValue(g, mapping), ToneMapValue(b, mapping)};
  }
  std::array<double, 3> v = {CleanChannel(r), CleanChannel(g), CleanChannel(b)};
  for (double& c : v) c *= mapping.exposure;
  const double y = Luminance(v[0], v[1], v[2]);
  if (!(y > 0.0) || !std::isfinite(y)) return {0.0f, 0.0f, 0.0f};  // black, or exposure <= 0
  // One factor for the three channels: the luminance goes through the curve, T(Y) / Y.
  const double scale = ToneCurve(y, mapping.op) / y;
  for (double& c : v) c *= scale;
  // T(Y) <= 1, but a saturated colour can still have a channel above 1 (pure blue at Y = 1 has
  // B = 13.9). Dividing by that channel keeps the chromaticity and makes it the brightest colour
  // of its hue the display has, where clamping each channel would shift the hue towards yellow,
  // cyan or white. Every channel stays non-decreasing in the exposure: c * min(T(Y)/Y, 1/max).
  const double largest = std::max({v[0], v[1], v[2]});
  if (largest > 1.0) {
    for (double& c : v) c /= largest;
  }
  std::array<float, 3> out{};
  for (int c = 0; c < 3; ++c) out[c] = static_cast<float>(EncodeDisplay(v[c], mapping));
  return out;
}

}  // namespace atmo
