// Night vision for display (docs/night.md, `--night-vision`): the loss of colour and the blue shift
// of human vision in the dark, applied to a linear sRGB image in cd/m^2 before tone mapping (the EXR
// stays physical).
//
// To use it:
//   const atmo::NightVision vision(parameters.wavelengths_nm);
//   atmo::ApplyNightVision(display, vision);   // linear sRGB, Y in cd/m^2, in place
//
// The method:
// - Scotopic luminance L_s per pixel. Each model channel's scotopic weight is 1700 lm/W x integral of
//   V'(lambda) (CIE 1951) over the channel's piece of the spectrum (SpectralConversion). The image
//   holds linear sRGB, so L_s is recovered as k . rgb, with k fitted by least squares to those
//   weights through the channels' sRGB weights. That is exact for 3 channels; for more it is the
//   best linear estimate from the colour.
// - Adaptation: the CIE 191:2010 mesopic system (MES2) at the image's adaptation luminances, the
//   log-averages of L_p (photopic) and L_s. It iterates m from 0.5 with
//   L_mes = (m L_p + (1 - m) L_s V'(555)) / (m + (1 - m) V'(555)) and m = 0.7670 + 0.3334 log10(L_mes),
//   m clamped to [0, 1]: photopic (m = 1) from about 5 cd/m^2, scotopic (m = 0) below about
//   0.005 cd/m^2 of scotopic luminance.
// - Each pixel is then seen with that adaptation. Its luminance is its mesopic one. A fraction m of it
//   keeps the pixel's colour; the rest, the rods' share, takes the blue-grey chromaticity
//   (x, y) = (0.25, 0.25) that Jensen et al. 2000 ("A Physically-Based Night Sky Model",
//   SIGGRAPH) use for scotopic display.
#pragma once

#include <span>

#include <glm/glm.hpp>

#include "atmo/image.h"

namespace atmo {

class NightVision {
 public:
  // For images rendered from channels at `wavelengths_nm`. Throws atmo::Error as SpectralConversion.
  explicit NightVision(std::span<const double> wavelengths_nm);
  // Scotopic luminance of a linear sRGB colour in cd/m^2 (clamped at 0).
  double ScotopicLuminance(const glm::dvec3& rgb) const;
  const glm::dvec3& scotopic_from_rgb() const { return k_; }

 private:
  glm::dvec3 k_{0.0};
};

// CIE 191:2010's photopic fraction m in [0, 1] for adaptation luminances L_p (photopic) and L_s
// (scotopic), both in cd/m^2; also gives the mesopic adaptation luminance.
double MesopicAdaptation(double photopic_cd_m2, double scotopic_cd_m2, double* mesopic_cd_m2 = nullptr);

// The image as seen at night (see the header comment), in place. Throws atmo::Error for an image that
// is not linear sRGB with 3 channels. Returns the image's photopic fraction m.
double ApplyNightVision(Image& linear_srgb, const NightVision& vision);

}  // namespace atmo
