// A program outside atmo, built against its installed package (tests/consumer/CMakeLists.txt or
// pkg-config): computes a real radiance through the public API and checks that it is physical.
//
//   atmo_consumer          the CPU model hillaire: finite, positive radiance, a blue clear sky,
//                          transmittance in (0, 1)
//   atmo_consumer --gl     also the GL backend (built with ATMO_CONSUMER_GL), against the CPU;
//                          exits 77 (skipped) where no GL context can be made
// Exits 0 when every check holds, 1 with a one-line reason otherwise.
#include <cmath>
#include <cstdio>
#include <cstring>
#include <exception>
#include <memory>
#include <string>
#include <vector>

#include <glm/glm.hpp>

#include <atmo/error.h>
#include <atmo/model.h>
#include <atmo/parameters.h>
#ifdef ATMO_CONSUMER_GL
#include <atmo/gl/context.h>
#include <atmo/gl/hillaire_gl.h>
#endif

namespace {

int Fail(const std::string& why) {
  std::fprintf(stderr, "atmo_consumer: %s\n", why.c_str());
  return 1;
}

}  // namespace

int main(int argc, char** argv) {
  const bool gl = argc > 1 && std::strcmp(argv[1], "--gl") == 0;
  try {
    const atmo::AtmosphereParameters earth = atmo::Preset("earth");
    const std::unique_ptr<atmo::Model> model = atmo::CreateModel("hillaire", earth);
    // Sun 60 degrees from the zenith in the north; the view 80 degrees from the zenith, east.
    const glm::dvec3 sun = atmo::DirectionFromZenithAzimuth(glm::radians(60.0), 0.0);
    const glm::dvec3 view = atmo::DirectionFromZenithAzimuth(glm::radians(80.0), glm::radians(90.0));
    const std::unique_ptr<atmo::SkyView> sky = model->View(/*altitude_m=*/0.0, sun);
    const std::size_t n = model->channel_count();
    std::vector<double> radiance(n), transmittance(n);
    sky->Radiance(view, radiance);
    sky->Transmittance(view, transmittance);

    std::size_t shortest = 0, longest = 0;  // channels of the shortest and longest wavelength
    for (std::size_t c = 0; c < n; ++c) {
      std::printf("%.0f nm: radiance %.6g sr^-1, transmittance %.6g\n", earth.wavelengths_nm[c], radiance[c],
                  transmittance[c]);
      if (!std::isfinite(radiance[c]) || radiance[c] <= 0.0) return Fail("radiance not finite and positive");
      if (!(transmittance[c] > 0.0 && transmittance[c] < 1.0)) return Fail("transmittance outside (0, 1)");
      if (earth.wavelengths_nm[c] < earth.wavelengths_nm[shortest]) shortest = c;
      if (earth.wavelengths_nm[c] > earth.wavelengths_nm[longest]) longest = c;
    }
    // Rayleigh scattering grows as lambda^-4: away from the sun the clear sky is bluest, and the
    // longest wavelength is the least attenuated.
    if (!(radiance[shortest] > radiance[longest])) return Fail("the clear sky is not bluer than it is red");
    if (!(transmittance[longest] > transmittance[shortest])) return Fail("red is attenuated more than blue");

    if (gl) {
#ifdef ATMO_CONSUMER_GL
      std::unique_ptr<atmo::gl::Context> context;
      try {
        context = std::make_unique<atmo::gl::Context>();
      } catch (const atmo::Error& error) {
        std::fprintf(stderr, "atmo_consumer: skipped: no GL context (%s)\n", error.what());
        return 77;
      }
      atmo::gl::HillaireSampler gpu(*context, earth);
      gpu.SetView(0.0, sun);
      std::vector<double> gpu_radiance, gpu_transmittance;
      gpu.Sample({&view, 1}, gpu_radiance, gpu_transmittance);
      if (gpu_radiance.size() != n || gpu_transmittance.size() != n) return Fail("GL sample: wrong channel count");
      for (std::size_t c = 0; c < n; ++c) {
        const double rel = std::abs(gpu_radiance[c] - radiance[c]) / radiance[c];
        std::printf("GL (%s) %.0f nm: radiance %.6g sr^-1 (rel. difference to CPU %.2g)\n",
                    context->renderer().c_str(), earth.wavelengths_nm[c], gpu_radiance[c], rel);
        // The backends agree to ~6e-4 on llvmpipe (float against double tables,
        // tests/gl_hillaire_test.cc); 1 % leaves room for a hardware GPU's coarser filtering.
        if (!std::isfinite(gpu_radiance[c]) || !(rel < 1e-2)) return Fail("GL radiance differs from the CPU's");
        if (!(std::abs(gpu_transmittance[c] - transmittance[c]) < 1e-3)) return Fail("GL transmittance differs");
      }
#else
      return Fail("--gl: built without atmo::gl");
#endif
    }
  } catch (const std::exception& error) {  // atmo::Error and what the standard library throws
    return Fail(error.what());
  }
  std::printf("atmo_consumer: ok\n");
  return 0;
}
