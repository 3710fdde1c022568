// The sun disc: Neckel and Labs' limb darkening against their published values, the
// normalisation that keeps the disc's irradiance 1, the cameras' pixel solid angles, and the
// images' disc pass (cpu/sun_disc.h): its energy at any resolution, its roundness, and every
// model's disc radiance.
#include <gtest/gtest.h>

#include <atomic>
#include <cmath>
#include <cstdio>
#include <memory>
#include <utility>
#include <vector>

#include "atmo/error.h"
#include "atmo/model.h"
#include "atmo/parameters.h"
#include "atmo/render.h"
#include "cpu/camera.h"
#include "cpu/sun_disc.h"
#include "shared/shared.h"
#include "sun_disc_integral.h"

namespace atmo {
namespace {

constexpr double kPi = 3.14159265358979323846;

// The mean of f over a cap of angular radius alpha by the midpoint rule in t = cos(theta), which
// is uniform in solid angle: independent of the closed form's substitution and quadrature.
double CapMeanByMidpoint(double wavelength_nm, double alpha, int n) {
  const double cos_alpha = std::cos(alpha);
  double sum = 0.0;
  for (int i = 0; i < n; ++i) {
    const double t = cos_alpha + (1.0 - cos_alpha) * (i + 0.5) / n;
    const double mu = shared::GetSunDiscSurfaceCosine(t, alpha);
    sum += shared::GetSunLimbDarkening(wavelength_nm, mu);
  }
  return sum / n;
}

TEST(SunLimbDarkening, IsOneAtTheCentreAndFallsToTheLimb) {
  for (double lambda : {300.0, 350.0, 372.0, 380.0, 400.0, 422.0, 440.0, 550.0, 680.0, 1100.0, 2000.0}) {
    EXPECT_NEAR(shared::GetSunLimbDarkening(lambda, 1.0), 1.0, 1e-12) << lambda;
    double previous = 0.0;
    for (double mu = 0.0; mu <= 1.0; mu += 0.05) {
      const double f = shared::GetSunLimbDarkening(lambda, mu);
      EXPECT_GT(f, previous) << lambda << " nm, mu " << mu;
      previous = f;
    }
  }
  // Blue darkens more towards the limb than red.
  EXPECT_LT(shared::GetSunLimbDarkening(440.0, 0.3), shared::GetSunLimbDarkening(550.0, 0.3));
  EXPECT_LT(shared::GetSunLimbDarkening(550.0, 0.3), shared::GetSunLimbDarkening(680.0, 0.3));
}

// Neckel and Labs 1994 (Solar Physics 153, 91), their table of fifth-degree coefficients at
// 559.95 nm: A = 0.26892, 1.34319, -1.58427, 1.91271, -1.31350, 0.37295, so that
// I(0.5) / I(1) = 0.7131, and the ratio of mean to central intensity 2 int f mu dmu = 0.8061;
// at 669.40 nm 0.34685, 1.37539, -2.04425, 2.70493, -1.94290, 0.55999 (0.7577; 0.8360). The fits
// in 1/lambda reproduce them to their own accuracy (f(0.5): +0.35 %, +0.14 %; flux ratio +0.25 %,
// +0.07 %, measured).
TEST(SunLimbDarkening, MatchesNeckelAndLabsTabulatedValues) {
  struct Row {
    double lambda_nm;
    double a[6];
    double flux_ratio;
  };
  for (const Row& row : {Row{559.95, {0.26892, 1.34319, -1.58427, 1.91271, -1.31350, 0.37295}, 0.8061},
                         Row{669.40, {0.34685, 1.37539, -2.04425, 2.70493, -1.94290, 0.55999}, 0.8360}}) {
    // The fits in 1/lambda stray most near the limb (2.2 % at mu = 0.1, 0.9 % at 0.3 measured).
    for (double mu : {0.1, 0.3, 0.5, 0.7, 0.9}) {
      double tabulated = 0.0;
      for (int k = 5; k >= 0; --k) tabulated = tabulated * mu + row.a[k];
      EXPECT_NEAR(shared::GetSunLimbDarkening(row.lambda_nm, mu), tabulated, (mu < 0.4 ? 0.025 : 0.005) * tabulated)
          << row.lambda_nm << " nm, mu " << mu;
    }
    // The flux ratio is the mean over a vanishing disc.
    const double mean = shared::GetSunDiscMeanLimbDarkening(row.lambda_nm, 1e-4, true);
    std::printf("%.2f nm: f(0.5) = %.4f, 2 int f mu dmu = %.4f (Neckel and Labs: %.4f)\n", row.lambda_nm,
                shared::GetSunLimbDarkening(row.lambda_nm, 0.5), mean, row.flux_ratio);
    EXPECT_NEAR(mean, row.flux_ratio, 0.004);
  }
}

TEST(SunLimbDarkening, GaussLegendreRuleIsExactToDegree15) {
  for (int k = 0; k <= 15; ++k) {
    double sum = 0.0;
    for (int i = 0; i < 8; ++i) {
      const double x = (i < 4 ? -1.0 : 1.0) * shared::GetGaussLegendre8Node(i % 4);
      sum += shared::GetGaussLegendre8Weight(i % 4) * std::pow(x, k);
    }
    EXPECT_NEAR(sum, k % 2 == 0 ? 2.0 / (k + 1) : 0.0, 1e-14) << k;
  }
}

// The normalisation: the disc's radiance integrated over its solid angle is exactly 1, for the
// Sun's size and a 20 degree disc, with and without limb darkening.
TEST(SunLimbDarkening, DiscIrradianceIsOne) {
  for (double alpha : {0.004675, 0.0045, glm::radians(10.0)}) {
    const double solid_angle = 2.0 * kPi * (1.0 - std::cos(alpha));
    for (double lambda : {440.0, 550.0, 680.0}) {
      const double mean = CapMeanByMidpoint(lambda, alpha, 200000);
      EXPECT_NEAR(shared::GetSunDiscMeanLimbDarkening(lambda, alpha, true), mean, 1e-7 * mean) << alpha;
      const double irradiance = shared::GetSunDiscCentreRadiance(lambda, alpha, true) * solid_angle * mean;
      EXPECT_NEAR(irradiance, 1.0, 1e-7) << "alpha " << alpha << ", " << lambda << " nm";
    }
    EXPECT_NEAR(shared::GetSunDiscCentreRadiance(550.0, alpha, false) * solid_angle, 1.0, 1e-11);
  }
}

shared::CameraParameters SharedCamera(CameraKind kind, int width, int height, double fov_deg = 90.0,
                                      double yaw_deg = 30.0, double pitch_deg = 10.0) {
  return ToSharedCamera(Camera{kind, width, height, fov_deg, yaw_deg, pitch_deg});
}

double SumOfPixelSolidAngles(const shared::CameraParameters& camera) {
  double sum = 0.0;
  for (int y = 0; y < camera.height; ++y) {
    for (int x = 0; x < camera.width; ++x) sum += shared::GetCameraPixelSolidAngle(camera, shared::ivec2(x, y));
  }
  return sum;
}

TEST(CameraPixelSolidAngle, SumsToTheSolidAngleTheCameraSees) {
  for (int width : {8, 256, 1023}) {
    EXPECT_NEAR(SumOfPixelSolidAngles(SharedCamera(CameraKind::kEquirect, width, width / 2 + 1)), 4.0 * kPi, 1e-11);
  }
  for (auto [width, height] : {std::pair{64, 64}, std::pair{257, 200}, std::pair{512, 512}}) {
    const double sum = SumOfPixelSolidAngles(SharedCamera(CameraKind::kFisheye, width, height));
    std::printf("fisheye %dx%d: sum of pixel solid angles / 2 pi - 1 = %.2e\n", width, height, sum / (2.0 * kPi) - 1.0);
    EXPECT_NEAR(sum, 2.0 * kPi, 2e-6 * 2.0 * kPi);
  }
  // A perspective image sees the rectangle |X| <= tan(fov / 2), |Y| <= tan(fov / 2) h / w.
  for (double fov : {1.0, 60.0, 150.0}) {
    const shared::CameraParameters camera = SharedCamera(CameraKind::kPerspective, 128, 72, fov);
    const double whole = 4.0 * shared::GetPerspectiveRectangleSolidAngle(camera.tan_half_fov, camera.tan_half_fov * 72.0 / 128.0);
    EXPECT_NEAR(SumOfPixelSolidAngles(camera), whole, 1e-9 * whole) << fov;
  }
}

// Each pixel's solid angle is the density integrated over it: close to the density at its centre.
TEST(CameraPixelSolidAngle, AgreesWithTheDensity) {
  for (const CameraKind kind : {CameraKind::kPerspective, CameraKind::kFisheye, CameraKind::kEquirect}) {
    const shared::CameraParameters camera = SharedCamera(kind, 200, 100);
    for (const auto& [x, y] : {std::pair{100, 50}, std::pair{130, 20}, std::pair{75, 61}}) {
      const double at_centre = shared::GetCameraSolidAngleDensity(camera, shared::vec2(x + 0.5, y + 0.5));
      EXPECT_NEAR(shared::GetCameraPixelSolidAngle(camera, shared::ivec2(x, y)), at_centre, 2e-4 * at_centre)
          << ToString(kind) << " " << x << " " << y;
    }
  }
}

TEST(CameraFragCoord, InvertsTheRayDirection) {
  for (const CameraKind kind : {CameraKind::kPerspective, CameraKind::kFisheye, CameraKind::kEquirect}) {
    const shared::CameraParameters camera = SharedCamera(kind, 320, 180, 75.0, 200.0, -20.0);
    for (const auto& [fx, fy] : {std::pair{0.3, 0.7}, std::pair{160.0, 90.0}, std::pair{250.25, 33.5}, std::pair{319.9, 179.2}}) {
      shared::vec3 d;
      if (!shared::GetCameraRayDirection(camera, shared::vec2(fx, fy), d)) continue;  // outside the fisheye
      shared::vec2 back;
      ASSERT_TRUE(shared::GetCameraFragCoordFromDirection(camera, d, back)) << ToString(kind);
      EXPECT_NEAR(back.x, fx, 1e-8) << ToString(kind);
      EXPECT_NEAR(back.y, fy, 1e-8) << ToString(kind);
    }
  }
}

// The disc's energy in an image, sum of value x pixel solid angle (per unit solar irradiance).
double ImageEnergy(const Image& image, const Camera& camera, int channel) {
  const shared::CameraParameters c = ToSharedCamera(camera);
  double sum = 0.0;
  for (int y = 0; y < image.height; ++y) {
    for (int x = 0; x < image.width; ++x) {
      const float v = image.pixels[(static_cast<std::size_t>(y) * image.width + x) * 3 + channel];
      if (v != 0.0f) sum += v * shared::GetCameraPixelSolidAngle(c, shared::ivec2(x, y));
    }
  }
  return sum;
}

using atmo::testing::DiscIrradiance;

class SunDiscImage : public ::testing::Test {
 protected:
  static void SetUpTestSuite() { model_ = CreateModel("hillaire", Preset("earth")).release(); }
  static void TearDownTestSuite() {
    delete model_;
    model_ = nullptr;
  }
  static Image DiscOnly(const SkyView& sky, const Camera& camera) {
    Image image(camera.width, camera.height, 3);
    const std::vector<double> one = {1.0, 1.0, 1.0};
    AddSunDisc(sky, camera, one, image);
    return image;
  }
  static inline Model* model_ = nullptr;
};

// The disc integrates to the transmitted direct irradiance within 1 % at any resolution, at every
// elevation (at 0.1 degrees the ground hides the disc's lower part) and wherever the disc falls
// between pixel centres; below a pixel across (equirect up to 512 px, fisheye 256) the disc is
// sampled rather than the pixels. (Sampled at pixel centres the error was -100 % at 256 and 512 px
// and +75 % at 1024 px.)
TEST_F(SunDiscImage, EnergyIsTheTransmittedIrradianceAtAnyResolution) {
  for (const double elevation : {30.0, 2.0, 0.3, 0.1, 61.7}) {
    for (const double azimuth : {180.0, 137.31}) {
      const auto sky = model_->View(0.0, SunDirection(elevation, azimuth));
      const std::vector<double> expected = DiscIrradiance(*sky);
      for (const CameraKind kind : {CameraKind::kEquirect, CameraKind::kFisheye}) {
        for (const int width : {16, 64, 256, 512, 1024, 2048}) {
          const Camera camera{kind, width, kind == CameraKind::kEquirect ? width / 2 : width, 90.0, 0.0, 0.0};
          const Image image = DiscOnly(*sky, camera);
          double worst = 0.0;
          for (int c = 0; c < 3; ++c) {
            const double error = ImageEnergy(image, camera, c) / expected[c] - 1.0;
            if (std::abs(error) > std::abs(worst)) worst = error;
          }
          std::printf("%-8s %4d px, sun at %5.2f deg elevation, azimuth %6.2f: energy error %+.3f %%\n",
                      std::string(ToString(kind)).c_str(), width, elevation, azimuth, 100.0 * worst);
          EXPECT_LT(std::abs(worst), 0.01) << ToString(kind) << " " << width << " elevation " << elevation;
        }
      }
    }
  }
}

// The image's disc is what RenderView adds: the sky and the pass, and nothing with sun_disc off.
TEST_F(SunDiscImage, RenderViewAddsThePassAndTheTermTurnsItOff) {
  const auto sky = model_->View(0.0, SunDirection(30.0, 180.0));
  const Camera camera{CameraKind::kEquirect, 256, 128, 90.0, 0.0, 0.0};
  const std::vector<double> one = {1.0, 1.0, 1.0};
  const Image with = RenderView(*sky, camera, RadianceTerms{true, true}, one);
  const Image without = RenderView(*sky, camera, RadianceTerms{false, true}, one);
  const Image disc = DiscOnly(*sky, camera);
  const std::vector<double> expected = DiscIrradiance(*sky);
  for (int c = 0; c < 3; ++c) {
    Image difference = with;
    for (std::size_t i = 0; i < difference.pixels.size(); ++i) difference.pixels[i] -= without.pixels[i];
    EXPECT_NEAR(ImageEnergy(difference, camera, c), ImageEnergy(disc, camera, c), 1e-5 * expected[c]);
  }
  // Without the disc, the sky near the sun is the sky: no pixel brighter than 20x the sky around.
  float brightest = 0.0f;
  for (float v : without.pixels) brightest = std::max(brightest, v);
  std::vector<double> l(3);
  sky->Radiance(SunDirection(35.0, 180.0), l);
  EXPECT_LT(brightest, 20.0 * l[2]);
}

// Second moments of the disc's pixel energy about its centroid.
struct Moments {
  double xx = 0.0, yy = 0.0, xy = 0.0;
  int partial = 0;  // pixels with 0 < value < half the largest
};

Moments DiscMoments(const Image& image, const Camera& camera) {
  const shared::CameraParameters c = ToSharedCamera(camera);
  double total = 0.0, mx = 0.0, my = 0.0;
  float largest = 0.0f;
  for (float v : image.pixels) largest = std::max(largest, v);
  std::vector<double> e(static_cast<std::size_t>(image.width) * image.height, 0.0);
  Moments m;
  for (int y = 0; y < image.height; ++y) {
    for (int x = 0; x < image.width; ++x) {
      const std::size_t i = static_cast<std::size_t>(y) * image.width + x;
      const float v = image.pixels[3 * i + 1];
      if (v > 0.0f && v < 0.5f * largest) ++m.partial;
      e[i] = v * shared::GetCameraPixelSolidAngle(c, shared::ivec2(x, y));
      total += e[i];
      mx += e[i] * (x + 0.5);
      my += e[i] * (y + 0.5);
    }
  }
  mx /= total;
  my /= total;
  for (int y = 0; y < image.height; ++y) {
    for (int x = 0; x < image.width; ++x) {
      const double w = e[static_cast<std::size_t>(y) * image.width + x] / total;
      m.xx += w * (x + 0.5 - mx) * (x + 0.5 - mx);
      m.yy += w * (y + 0.5 - my) * (y + 0.5 - my);
      m.xy += w * (x + 0.5 - mx) * (y + 0.5 - my);
    }
  }
  return m;
}

// <r^2> / R^2 of the limb-darkened disc at 550 nm, weighted by its radiance: int s^3 f ds /
// int s f ds with mu = sqrt(1 - s^2) (1/2 for a uniform disc).
double LimbDarkenedRadialMoment() {
  double num = 0.0, den = 0.0;
  for (int i = 0; i < 100000; ++i) {
    const double s = (i + 0.5) / 100000;
    const double f = shared::GetSunLimbDarkening(550.0, std::sqrt(1.0 - s * s));
    num += s * s * s * f;
    den += s * f;
  }
  return num / den;
}

// At 1280 x 720 the disc is round: equal second moments in x and y, no cross moment, the radial
// moment of the limb-darkened disc (plus the pixels' own 1/12 px^2 per axis), soft edges.
// (Sampled at pixel centres it was a hard block of 6 pixels.)
TEST_F(SunDiscImage, IsRoundInAPerspectiveView) {
  const auto sky = model_->View(0.0, SunDirection(20.0, 180.0));
  for (const double fov : {90.0, 10.0}) {
    // The sun a fraction of a pixel off the image centre, where the projection does not stretch it.
    const double pixel_deg = glm::degrees(2.0 * std::tan(glm::radians(fov / 2.0)) / 1280.0);
    const Camera camera{CameraKind::kPerspective, 1280, 720, fov, 180.0 + 0.37 * pixel_deg, 20.0 - 0.21 * pixel_deg};
    const Image image = DiscOnly(*sky, camera);
    const Moments m = DiscMoments(image, camera);
    const double radius_px = sky->sun_angular_radius_rad() / glm::radians(pixel_deg);
    const double expected = LimbDarkenedRadialMoment() * radius_px * radius_px + 1.0 / 6.0;
    std::printf("perspective fov %.0f: disc %.1f px across, second moments xx %.3f yy %.3f xy %.4f px^2 "
                "(yy / xx - 1 = %+.2f %%; xx + yy %.3f, expected %.3f), %d partly covered pixels\n",
                fov, 2.0 * radius_px, m.xx, m.yy, m.xy, 100.0 * (m.yy / m.xx - 1.0), m.xx + m.yy, expected, m.partial);
    EXPECT_NEAR(m.yy / m.xx, 1.0, 0.03);
    EXPECT_LT(std::abs(m.xy), 0.03 * m.xx);
    EXPECT_NEAR(m.xx + m.yy, expected, 0.03 * expected);
    EXPECT_GE(m.partial, 8);
  }
}

// A large disc: its inside pixels hold the limb-darkened radiance of their centre, L_c f(mu) T.
TEST_F(SunDiscImage, LargeDiscPixelsHoldTheDiscRadiance) {
  const auto sky = model_->View(0.0, SunDirection(20.0, 180.0));
  const Camera camera{CameraKind::kPerspective, 128, 128, 1.0, 180.0, 20.0};  // 0.53 deg over 68 px
  const Image image = DiscOnly(*sky, camera);
  const shared::CameraParameters c = ToSharedCamera(camera);
  std::vector<double> l(3);
  for (const auto& [x, y] : {std::pair{64, 64}, std::pair{80, 50}, std::pair{40, 70}}) {
    // The pixel's mean radiance on a fine grid, weighted by solid angle.
    std::vector<double> mean(3, 0.0);
    double weight = 0.0;
    for (int j = 0; j < 32; ++j) {
      for (int i = 0; i < 32; ++i) {
        const shared::vec2 frag(x + (i + 0.5) / 32, y + (j + 0.5) / 32);
        shared::vec3 view;
        shared::GetCameraRayDirection(c, frag, view);
        sky->SunDiscRadiance(view, l);
        const double density = shared::GetCameraSolidAngleDensity(c, frag);
        for (int ch = 0; ch < 3; ++ch) mean[ch] += l[ch] * density;
        weight += density;
      }
    }
    for (int ch = 0; ch < 3; ++ch) {
      mean[ch] /= weight;
      EXPECT_NEAR(image.pixels[(static_cast<std::size_t>(y) * 128 + x) * 3 + ch], mean[ch], 5e-4 * mean[ch])
          << x << " " << y;
    }
  }
}

// Every model's disc: at the centre the normalised central radiance times the transmittance, and
// towards the limb darkened by f(mu) per channel.
TEST(SunDiscRadiance, EveryModelDrawsTheLimbDarkenedDisc) {
  struct Case {
    const char* model;
    const char* preset;
    ModelOptions options;
    double altitude_m;
  };
  for (const Case& m : {Case{"hillaire", "earth", {}, 0.0}, Case{"elek", "earth", {{"size", "6x20x7"}, {"orders", "1"}}, 0.0},
                        Case{"simple", "simple", {}, -0.3}, Case{"reference", "earth", {}, 0.0}}) {
    const AtmosphereParameters p = Preset(m.preset);
    const auto model = CreateModel(m.model, p, m.options);
    const glm::dvec3 sun = SunDirection(25.0, 180.0);
    const auto sky = model->View(m.altitude_m, sun);
    EXPECT_EQ(sky->sun_angular_radius_rad(), p.sun_angular_radius_rad) << m.model;
    std::vector<double> disc(3), t(3);
    sky->SunDiscRadiance(sun, disc);
    sky->Transmittance(sun, t);
    for (int c = 0; c < 3; ++c) {
      const double centre = shared::GetSunDiscCentreRadiance(p.wavelengths_nm[c], p.sun_angular_radius_rad, true);
      EXPECT_NEAR(disc[c], centre * t[c], 1e-6 * disc[c]) << m.model << " channel " << c;
    }
    // At theta = 0.9 alpha from the centre, mu = sqrt(1 - 0.81) (to the sines of small angles).
    const double alpha = p.sun_angular_radius_rad;
    const glm::dvec3 e = glm::normalize(glm::cross(sun, glm::dvec3(0.0, 0.0, 1.0)));
    const glm::dvec3 limb = std::cos(0.9 * alpha) * sun + std::sin(0.9 * alpha) * e;  // level with the centre
    std::vector<double> edge(3), t_edge(3);
    sky->SunDiscRadiance(limb, edge);
    sky->Transmittance(limb, t_edge);
    const double mu = shared::GetSunDiscSurfaceCosine(glm::dot(limb, sun), alpha);
    EXPECT_NEAR(mu, std::sqrt(1.0 - 0.81), 1e-4);
    for (int c = 0; c < 3; ++c) {
      EXPECT_NEAR(edge[c] / t_edge[c] / (disc[c] / t[c]), shared::GetSunLimbDarkening(p.wavelengths_nm[c], mu), 1e-6)
          << m.model << " channel " << c;
    }
    // Off the disc: nothing.
    sky->SunDiscRadiance(std::cos(1.01 * alpha) * sun + std::sin(1.01 * alpha) * e, edge);
    for (double v : edge) EXPECT_EQ(v, 0.0) << m.model;
  }
}

TEST(SunDiscRadiance, LimbDarkeningOffGivesTheUniformDisc) {
  AtmosphereParameters p = Preset("earth");
  p.sun_limb_darkening = false;
  const auto model = CreateModel("hillaire", p);
  const glm::dvec3 sun = SunDirection(25.0, 180.0);
  const auto sky = model->View(0.0, sun);
  const double alpha = p.sun_angular_radius_rad;
  const glm::dvec3 e = glm::normalize(glm::cross(sun, glm::dvec3(0.0, 0.0, 1.0)));
  std::vector<double> disc(3), t(3);
  for (const double theta : {0.0, 0.5 * alpha, 0.99 * alpha}) {
    const glm::dvec3 view = std::cos(theta) * sun + std::sin(theta) * e;
    sky->SunDiscRadiance(view, disc);
    sky->Transmittance(view, t);
    for (int c = 0; c < 3; ++c) EXPECT_NEAR(disc[c], t[c] / (2.0 * kPi * (1.0 - std::cos(alpha))), 1e-9 * disc[c]);
  }
  EXPECT_FALSE(FromJson(ToJson(p)).sun_limb_darkening);
  EXPECT_THROW(FromJson("{\"sun_limb_darkening\": 1}"), Error);
}

// The progressive renderer adds the same deterministic disc: with and without it, the images
// differ by the disc's energy.
TEST(SunDiscProgressive, AddsTheDiscPass) {
  const auto model = CreateModel("reference", Preset("earth"), {{"samples", "2"}});
  RenderSettings s;
  s.camera = {CameraKind::kEquirect, 48, 24, 90.0, 0.0, 0.0};
  s.sun_elevation_deg = 30.0;
  s.terms.ground = false;
  ProgressiveSettings progressive;
  progressive.samples_per_pixel = 2;
  progressive.first_pass_samples = 2;
  const Image with = RenderProgressive(*model, s, progressive).radiance;
  s.terms.sun_disc = false;
  const Image without = RenderProgressive(*model, s, progressive).radiance;
  const auto sky = model->View(0.0, SunDirection(30.0, 180.0));
  const std::vector<double> expected = DiscIrradiance(*sky, 40, 40);
  Image difference = with;
  for (std::size_t i = 0; i < difference.pixels.size(); ++i) difference.pixels[i] -= without.pixels[i];
  for (int c = 0; c < 3; ++c) {
    EXPECT_NEAR(ImageEnergy(difference, s.camera, c), expected[c], 0.01 * expected[c]) << c;
  }
}

}  // namespace
}  // namespace atmo

namespace atmo {
namespace {

// RenderView's progress callback: counts that only grow, never beyond the image's rows, ending at
// (rows, rows), one call at a time, and an image equal to the one rendered without it.
TEST_F(SunDiscImage, RenderViewReportsRowProgressWithoutChangingTheImage) {
  const auto sky = model_->View(0.0, SunDirection(30.0, 180.0));
  const Camera camera{CameraKind::kPerspective, 64, 48, 90.0, 180.0, 10.0};
  const std::vector<double> one = {1.0, 1.0, 1.0};
  std::vector<std::pair<int, int>> calls;
  std::atomic<int> running{0};
  bool overlapped = false;
  const Image reported = RenderView(*sky, camera, RadianceTerms{}, one, [&](int done, int total) {
    if (running.fetch_add(1) != 0) overlapped = true;
    calls.emplace_back(done, total);
    running.fetch_sub(1);
  });
  const Image plain = RenderView(*sky, camera, RadianceTerms{}, one);
  EXPECT_EQ(reported.pixels, plain.pixels);
  ASSERT_FALSE(calls.empty());
  EXPECT_FALSE(overlapped);
  EXPECT_EQ(calls.back(), std::make_pair(48, 48));
  for (const auto& [done, total] : calls) {
    EXPECT_EQ(total, 48);
    EXPECT_GE(done, 1);
    EXPECT_LE(done, 48);
  }
}

}  // namespace
}  // namespace atmo
