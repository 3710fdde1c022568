// atmo_spectral_error: how many wavelengths a spectral render needs. Renders one equirect sky
// (128x64, the sun disc left out, the lit ground in) of model hillaire for several sun elevations
// with N wavelengths and with N = 81, and prints the colour difference (CIEDE2000) and the
// relative luminance error per pixel, median and 95th percentile. Also the 3-channel preset
// `earth` (680, 550, 440 nm, converted by atmo::SpectralConversion) against the same atmosphere
// resampled to 81 wavelengths. The Lab white is D65 at the luminance of the reference image's
// 99th percentile pixel, the white of a display exposed for that sky.
//
// Run: build/bench/atmo_spectral_error   (docs/spectral.md keeps its output)
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <vector>

#include "atmo/colour.h"
#include "atmo/render.h"
#include "atmo/spectrum.h"

namespace {

struct Errors {
  double delta_e_median, delta_e_p95, luminance_median, luminance_p95;
};

double Percentile(std::vector<double> values, double p) {
  std::sort(values.begin(), values.end());
  return values[static_cast<std::size_t>(p * (values.size() - 1))];
}

atmo::Image RenderXyz(const atmo::AtmosphereParameters& parameters, double sun_elevation_deg) {
  atmo::AtmosphereParameters p = parameters;
  p.solar_irradiance.assign(p.channel_count(), 1.0);
  const auto model = atmo::CreateModel("hillaire", p);
  atmo::RenderSettings settings;
  settings.camera = {atmo::CameraKind::kEquirect, 128, 64};
  settings.sun_elevation_deg = sun_elevation_deg;
  settings.terms.sun_disc = false;
  const atmo::Image relative = atmo::Render(*model, settings);
  return atmo::ConvertImage(relative, atmo::SpectralConversion(p.wavelengths_nm), atmo::ImageColour::kXyz);
}

Errors Compare(const atmo::Image& test, const atmo::Image& reference) {
  const std::size_t pixels = static_cast<std::size_t>(reference.width) * reference.height;
  std::vector<double> y;
  for (std::size_t i = 0; i < pixels; ++i) y.push_back(reference.pixels[3 * i + 1]);
  const double white_y = Percentile(y, 0.99);
  const glm::dvec3 white = white_y * glm::dvec3(0.3127 / 0.3290, 1.0, (1.0 - 0.3127 - 0.3290) / 0.3290);
  std::vector<double> delta_e, luminance;
  for (std::size_t i = 0; i < pixels; ++i) {
    const glm::dvec3 a(test.pixels[3 * i], test.pixels[3 * i + 1], test.pixels[3 * i + 2]);
    const glm::dvec3 b(reference.pixels[3 * i], reference.pixels[3 * i + 1], reference.pixels[3 * i + 2]);
    delta_e.push_back(atmo::DeltaE2000(atmo::XyzToLab(a, white), atmo::XyzToLab(b, white)));
    if (b.y > 0.0) luminance.push_back(std::abs(a.y / b.y - 1.0));
  }
  return {Percentile(delta_e, 0.5), Percentile(delta_e, 0.95), Percentile(luminance, 0.5), Percentile(luminance, 0.95)};
}

}  // namespace

int main() {
  const double elevations[] = {60.0, 30.0, 10.0, 2.0, -4.0};
  std::printf("atmosphere, N, sun elevation (deg), dE2000 median, dE2000 p95, |dY/Y| median %%, |dY/Y| p95 %%\n");
  for (const bool physical : {true, false}) {
    const auto make = [&](int n) {
      if (physical) {
        atmo::SpectralEarthSettings s;
        s.wavelength_count = n;
        return atmo::EarthSpectral(s);
      }
      return atmo::MakeSpectral(atmo::Preset("earth"), n);
    };
    const char* name = physical ? "earth-spectral" : "earth resampled";
    for (double elevation : elevations) {
      const atmo::Image reference = RenderXyz(make(81), elevation);
      if (!physical) {
        const Errors e = Compare(RenderXyz(atmo::Preset("earth"), elevation), reference);
        std::printf("earth (680/550/440 nm), 3, %.0f, %.2f, %.2f, %.2f, %.2f\n", elevation, e.delta_e_median,
                    e.delta_e_p95, 100.0 * e.luminance_median, 100.0 * e.luminance_p95);
      }
      for (int n : {4, 6, 8, 12, 15, 16, 18, 24, 32, 48}) {
        const Errors e = Compare(RenderXyz(make(n), elevation), reference);
        std::printf("%s, %d, %.0f, %.2f, %.2f, %.2f, %.2f\n", name, n, elevation, e.delta_e_median, e.delta_e_p95,
                    100.0 * e.luminance_median, 100.0 * e.luminance_p95);
      }
    }
  }
  return 0;
}
