// From the model's per-channel radiance to light as people measure and see it: spectral radiance
// (W m^-2 sr^-1 nm^-1), radiance (W m^-2 sr^-1), CIE 1931 XYZ, luminance (cd/m^2) and linear
// Rec.709 / sRGB (D65) colour; and the CIEDE2000 colour difference.
//
// To use it:
//   atmo::SpectralConversion convert(parameters.wavelengths_nm);
//   std::vector<double> r(n);  sky->Radiance(view, r);       // sr^-1 per unit solar irradiance
//   double cd_m2 = convert.Luminance(r);
//   glm::dvec3 rgb = convert.LinearSrgb(r);                   // Y of rgb = cd_m2
//   atmo::Image display = atmo::ConvertImage(relative_image, convert, atmo::ImageColour::kLinearSrgb);
//
// The method (docs/spectral.md): the channels sample the spectrum at their wavelengths; between
// them it is linear in wavelength, beyond the first and last channel it is held. That relative
// spectrum r(lambda) times the solar spectrum E(lambda) (SolarSpectralIrradiance) is the spectral
// radiance L(lambda), integrated against the CIE 1931 functions over 360..830 nm at 1 nm. The
// result is linear in the channels, so it is a fixed 3 x N matrix per channel set. A spectral
// atmosphere (many channels) and a 3-channel preset go through the same formula; with 3 channels
// the spectrum between the samples is only a guess, and docs/spectral.md gives the colour error
// that this costs.
#pragma once

#include <span>
#include <string_view>
#include <vector>

#include <glm/glm.hpp>

#include "atmo/image.h"

namespace atmo {

// What the numbers of an output hold.
enum class RadianceUnit {
  kRelative,   // the model's radiance, sr^-1 per unit solar irradiance, times solar_irradiance
  kRadiance,   // spectral radiance per channel, W m^-2 sr^-1 nm^-1 (its integral: W m^-2 sr^-1)
  kLuminance,  // luminance, cd/m^2 (colour images: linear sRGB or XYZ with Y in cd/m^2)
};
RadianceUnit ParseRadianceUnit(std::string_view name);  // "relative", "radiance", "luminance"
std::string_view ToString(RadianceUnit unit);
// The unit as written into outputs (EXR atmo:radianceUnit, CSV headers), e.g. "cd/m^2".
std::string_view UnitSymbol(RadianceUnit unit);

class SpectralConversion {
 public:
  // Throws atmo::Error for no wavelengths or a non-positive or non-finite one.
  explicit SpectralConversion(std::span<const double> wavelengths_nm);

  std::size_t channel_count() const { return wavelengths_nm_.size(); }
  // CIE XYZ of the spectral radiance, in W m^-2 sr^-1 (weighted by the colour-matching functions;
  // times kMaxLuminousEfficacy gives Y in cd/m^2).
  glm::dvec3 Xyz(std::span<const double> relative) const;
  // Luminance in cd/m^2.
  double Luminance(std::span<const double> relative) const;
  // Scotopic luminance in scotopic cd/m^2: 1700 lm/W x integral of V'(lambda) L(lambda)
  // (ScotopicEfficiency, include/atmo/spectrum.h).
  double ScotopicLuminance(std::span<const double> relative) const;
  // Its weights: ScotopicLuminance(r) = sum_i scotopic_weights()[i] * r_i.
  const std::vector<double>& scotopic_weights() const { return scotopic_weights_; }
  // Radiance integrated over 360..830 nm, W m^-2 sr^-1.
  double Radiance(std::span<const double> relative) const;
  // Linear Rec.709 / sRGB (D65) whose luminance is in cd/m^2.
  glm::dvec3 LinearSrgb(std::span<const double> relative) const;
  // The spectral radiance of one channel, W m^-2 sr^-1 nm^-1: relative x E(lambda_channel).
  double SpectralRadiance(std::size_t channel, double relative) const;
  // The solar spectral irradiance at each channel's wavelength, W m^-2 nm^-1.
  const std::vector<double>& solar_irradiance() const { return solar_irradiance_; }
  // The weights: Xyz(r) = sum_i xyz_weights()[i] * r_i (W m^-2 sr^-1).
  const std::vector<glm::dvec3>& xyz_weights() const { return xyz_weights_; }

 private:
  std::vector<double> wavelengths_nm_;
  std::vector<glm::dvec3> xyz_weights_;
  std::vector<double> radiance_weights_;
  std::vector<double> scotopic_weights_;
  std::vector<double> solar_irradiance_;
};

// CIE XYZ -> linear Rec.709 / sRGB with the D65 white (IEC 61966-2-1), and back.
glm::dvec3 XyzToLinearSrgb(const glm::dvec3& xyz);
glm::dvec3 LinearSrgbToXyz(const glm::dvec3& rgb);

// Radiance's (Ward's Radiance lighting system) RGB: its primaries (x, y) = (0.640, 0.330),
// (0.290, 0.600), (0.150, 0.060) with an equal-energy white, in its "watts" of 179 lm each, so
// that its luminance 179 (0.265 R + 0.670 G + 0.065 B) is the colour's Y. `xyz_cd_m2`: CIE XYZ with
// Y in cd/m^2 (or lux). The inverse converts back.
inline constexpr double kRadianceWhiteEfficacy = 179.0;
glm::dvec3 XyzToRadianceRgb(const glm::dvec3& xyz_cd_m2);
glm::dvec3 RadianceRgbToXyz(const glm::dvec3& rgb);
// XyzToRadianceRgb, a colour outside the gamut (a negative component) moved towards the grey of
// its luminance until it is inside, its luminance kept; 0 for a luminance <= 0.
glm::dvec3 XyzToRadianceRgbInGamut(const glm::dvec3& xyz_cd_m2);

// The colour of a converted image.
enum class ImageColour {
  kLinearSrgb,  // R, G, B: linear Rec.709 / sRGB (D65), Y in cd/m^2
  kXyz,         // X, Y, Z: CIE 1931, Y in cd/m^2
  kSpectral,    // one channel per wavelength, W m^-2 sr^-1 nm^-1
};

// One point of `atmo sample` in `unit`, from the model's per-channel relative radiance,
// transmittance and standard error: per channel for relative and radiance (radiance and error
// times the solar spectral irradiance), one value for luminance (cd/m^2, the luminous
// transmittance, and the luminance's standard error, the channels' independent variances
// added). The outputs hold SampleChannels(unit, channels) values each. Shared by the command
// line, the Python module and the web build, so that the three report the same numbers.
std::size_t SampleChannels(RadianceUnit unit, std::size_t channels);
void ConvertSample(const SpectralConversion& convert, RadianceUnit unit, std::span<const double> radiance,
                   std::span<const double> transmittance, std::span<const double> standard_error,
                   std::span<double> out_radiance, std::span<double> out_transmittance, std::span<double> out_error);

// The per-channel weights of ConvertImage for kLinearSrgb or kXyz (Y in cd/m^2): output k of a
// pixel is sum_c weights[c][k] r_c. Throws atmo::Error for kSpectral.
std::vector<glm::vec3> ColourWeights(const SpectralConversion& convert, ImageColour colour);

// Converts an image whose channels hold the model's relative radiance (sr^-1 per unit solar
// irradiance, one per wavelength of `convert`) into `colour`; alpha is kept and the colour space
// is recorded in Image::colour_space. Throws atmo::Error for a channel-count mismatch.
Image ConvertImage(const Image& relative, const SpectralConversion& convert, ImageColour colour);
// The standard error of ConvertImage(relative) from the per-channel standard errors of
// `relative`, for estimates whose channels are independent (the reference traces each channel's
// paths apart): sigma_k = sqrt(sum_c (w_kc sigma_c)^2) for output channel k.
Image ConvertStandardError(const Image& standard_error, const SpectralConversion& convert, ImageColour colour);

// CIELAB of an XYZ colour against the white `white_xyz` (CIE 1976), and the CIEDE2000 colour
// difference of two Lab colours (Sharma, Wu and Dalal 2005, with kL = kC = kH = 1).
glm::dvec3 XyzToLab(const glm::dvec3& xyz, const glm::dvec3& white_xyz);
double DeltaE2000(const glm::dvec3& lab_1, const glm::dvec3& lab_2);

}  // namespace atmo
