// Night vision for display (include/atmo/night_vision.h).
#include "atmo/night_vision.h"

#include <algorithm>
#include <cmath>
#include <vector>

#include "atmo/colour.h"
#include "atmo/error.h"
#include "atmo/spectrum.h"

namespace atmo {
namespace {

constexpr double kScotopicAt555 = 0.402;  // V'(555 nm) = 683 / 1700

// Rec.709 luminance weights.
double Photopic(const glm::dvec3& rgb) { return 0.2126 * rgb.x + 0.7152 * rgb.y + 0.0722 * rgb.z; }

}  // namespace

NightVision::NightVision(std::span<const double> wavelengths_nm) {
  const SpectralConversion convert(wavelengths_nm);
  const std::vector<glm::vec3> rgb = ColourWeights(convert, ImageColour::kLinearSrgb);
  const std::vector<double>& s = convert.scotopic_weights();
  // Least squares: the k minimising sum_c (rgb_c . k - s_c)^2, from the normal equations.
  glm::dmat3 gram(0.0);
  glm::dvec3 rhs(0.0);
  for (std::size_t c = 0; c < s.size(); ++c) {
    const glm::dvec3 w(rgb[c]);
    gram += glm::outerProduct(w, w);
    rhs += w * s[c];
  }
  if (std::abs(glm::determinant(gram)) > 0.0) {
    k_ = glm::inverse(gram) * rhs;
  } else {
    // Fewer than 3 independent channels: the scotopic over photopic ratio of a grey sky.
    double photopic = 0.0, scotopic = 0.0;
    for (std::size_t c = 0; c < s.size(); ++c) {
      photopic += Photopic(glm::dvec3(rgb[c]));
      scotopic += s[c];
    }
    k_ = glm::dvec3(0.2126, 0.7152, 0.0722) * (photopic > 0.0 ? scotopic / photopic : 1.0);
  }
}

double NightVision::ScotopicLuminance(const glm::dvec3& rgb) const { return std::max(0.0, glm::dot(k_, rgb)); }

double MesopicAdaptation(double photopic, double scotopic, double* mesopic) {
  photopic = std::max(photopic, 0.0);
  scotopic = std::max(scotopic, 0.0);
  double m = 0.5;
  double l = 0.0;
  for (int i = 0; i < 50; ++i) {
    l = (m * photopic + (1.0 - m) * scotopic * kScotopicAt555) / (m + (1.0 - m) * kScotopicAt555);
    const double next = l > 0.0 ? std::clamp(0.7670 + 0.3334 * std::log10(l), 0.0, 1.0) : 0.0;
    if (std::abs(next - m) < 1e-9) {
      m = next;
      break;
    }
    m = next;
  }
  if (mesopic != nullptr) {
    *mesopic = (m * photopic + (1.0 - m) * scotopic * kScotopicAt555) / (m + (1.0 - m) * kScotopicAt555);
  }
  return m;
}

double ApplyNightVision(Image& image, const NightVision& vision) {
  if (image.channels != 3 || image.colour_space != ColourSpace::kLinearSrgb) {
    throw Error("night vision needs a linear sRGB image in cd/m^2");
  }
  const std::size_t pixels = static_cast<std::size_t>(image.width) * image.height;
  // The adaptation: log-averages of the photopic and scotopic luminance over the seen pixels.
  double log_p = 0.0, log_s = 0.0;
  std::size_t count = 0;
  for (std::size_t i = 0; i < pixels; ++i) {
    if (!image.alpha.empty() && image.alpha[i] == 0.0f) continue;
    const glm::dvec3 rgb(image.pixels[3 * i], image.pixels[3 * i + 1], image.pixels[3 * i + 2]);
    const double p = Photopic(rgb);
    const double s = vision.ScotopicLuminance(rgb);
    if (!(p > 0.0) || !(s > 0.0) || !std::isfinite(p) || !std::isfinite(s)) continue;
    log_p += std::log(p);
    log_s += std::log(s);
    ++count;
  }
  if (count == 0) return 1.0;
  const double m = MesopicAdaptation(std::exp(log_p / count), std::exp(log_s / count));
  // The rods' colour: chromaticity (0.25, 0.25) at luminance 1.
  const glm::dvec3 blue = XyzToLinearSrgb(glm::dvec3(1.0, 1.0, 2.0));  // x = y = 0.25: X = Y = 1, Z = 2
  const glm::dvec3 rod = blue / Photopic(blue);
  const double denominator = m + (1.0 - m) * kScotopicAt555;
  for (std::size_t i = 0; i < pixels; ++i) {
    float* px = &image.pixels[3 * i];
    const glm::dvec3 rgb(px[0], px[1], px[2]);
    const double p = Photopic(rgb);
    const double s = vision.ScotopicLuminance(rgb);
    // The cones' part keeps the colour (scaled), the rods' part is blue-grey.
    const glm::dvec3 cones = p > 0.0 ? rgb * (m / denominator) : glm::dvec3(0.0);
    const glm::dvec3 rods = rod * ((1.0 - m) * s * kScotopicAt555 / denominator);
    const glm::dvec3 seen = cones + rods;
    for (int k = 0; k < 3; ++k) px[k] = static_cast<float>(std::max(0.0, seen[k]));
  }
  return m;
}

}  // namespace atmo
