// Auto-exposure metered on the GPU (src/atmo/gl/exposure_gl.h) against AutoExposureEv100 of the
// same pixels on the CPU, and the GPU timer queries read later (src/atmo/gl/timer_queries.h).
#include <cmath>
#include <cstdio>
#include <limits>
#include <memory>
#include <random>
#include <vector>

#include <epoxy/gl.h>
#include <glm/glm.hpp>
#include <gtest/gtest.h>

#include "atmo/image.h"
#include "atmo/timing.h"
#include "gl/context.h"
#include "gl/exposure_gl.h"
#include "gl/resources.h"
#include "gl/timer_queries.h"
#include "gl_test_context.h"

namespace atmo::gl {
namespace {

// An rgba32f texture holding `rgba` (width x height texels).
GpuTexture Texture(int width, int height, const std::vector<float>& rgba) {
  GpuTexture texture = GpuTexture::Make2D({width, height});
  glTextureSubImage2D(texture.id(), 0, 0, 0, width, height, GL_RGBA, GL_FLOAT, rgba.data());
  return texture;
}

// A sky-like frame: luminances log-uniform over `stops` stops around 2^centre, a bright disc of
// `sun_share` of the pixels at 2^(centre + 20), and some pixels no meter may count (0, negative,
// NaN, infinite). Alpha 1, or 0 on the left half when `left_outside` (with absurd values there).
struct Frame {
  int width = 0;
  int height = 0;
  std::vector<float> rgba;
};
Frame SkyLike(int width, int height, double centre, double stops, double sun_share, bool left_outside,
              unsigned seed) {
  Frame f{width, height, std::vector<float>(static_cast<std::size_t>(width) * height * 4)};
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  for (int y = 0; y < height; ++y) {
    for (int x = 0; x < width; ++x) {
      float* p = &f.rgba[4 * (static_cast<std::size_t>(y) * width + x)];
      const double r = u(rng);
      double l = std::exp2(centre + stops * (u(rng) - 0.5));
      if (r < sun_share) l = std::exp2(centre + 20.0);
      // A colour of that luminance-ish (the meter weights it exactly).
      p[0] = static_cast<float>(l * (0.6 + 0.8 * u(rng)));
      p[1] = static_cast<float>(l);
      p[2] = static_cast<float>(l * (0.6 + 0.8 * u(rng)));
      p[3] = 1.0f;
      const double bad = u(rng);
      if (bad < 0.01) p[0] = p[1] = p[2] = 0.0f;
      else if (bad < 0.02) p[1] = -1.0f, p[0] = p[2] = 0.0f;
      else if (bad < 0.025) p[1] = std::numeric_limits<float>::quiet_NaN();
      else if (bad < 0.03) p[0] = p[1] = p[2] = std::numeric_limits<float>::infinity();
      if (left_outside && x < width / 2) {
        p[3] = 0.0f;
        p[0] = p[1] = p[2] = 1e30f;  // would swing the mean if counted
      }
    }
  }
  return f;
}

// The CPU's image of the linear sRGB colour that the meter sees: sum over batches of weights[b]
// times batch b's rgb, alpha where `alpha`.
Image Composite(const std::vector<Frame>& batches, const std::vector<glm::mat3>& weights, bool alpha) {
  const Frame& first = batches.front();
  Image image(first.width, first.height, 3);
  const std::size_t n = static_cast<std::size_t>(first.width) * first.height;
  if (alpha) image.alpha.assign(n, 0.0f);
  for (std::size_t i = 0; i < n; ++i) {
    glm::vec3 rgb(0.0f);
    for (std::size_t b = 0; b < batches.size(); ++b) {
      const float* p = &batches[b].rgba[4 * i];
      rgb += weights[b] * glm::vec3(p[0], p[1], p[2]);
    }
    for (int c = 0; c < 3; ++c) image.pixels[3 * i + c] = rgb[c];
    if (alpha) image.alpha[i] = first.rgba[4 * i + 3];
  }
  return image;
}

// Binning moves each value by at most half a bin (1/64 stop), and the percentiles with them.
constexpr double kBinningBound = 1.0 / 64.0;

TEST(GlExposureMeter, MatchesTheCpuMeterOfTheSamePixels) {
  ATMO_REQUIRE_GL_CONTEXT(context);
  context.MakeCurrent();
  ExposureMeter meter;
  const std::vector<glm::mat3> identity = {glm::mat3(1.0f)};
  struct Case {
    const char* what;
    double centre;
    double stops;
    double sun_share;
  };
  for (const Case& c : {Case{"noon sky (cd/m2)", 13.0, 4.0, 0.005}, Case{"twilight", -2.0, 10.0, 0.0},
                        Case{"night", -12.0, 6.0, 0.03}, Case{"sun over 5% of the frame", 12.0, 3.0, 0.05}}) {
    const Frame f = SkyLike(301, 173, c.centre, c.stops, c.sun_share, false, 7);
    const GpuTexture texture = Texture(f.width, f.height, f.rgba);
    const GpuTexture* frames[] = {&texture};
    meter.Meter(frames, identity, false);
    const std::optional<ExposureMeter::Reading> reading = meter.Latest(true);
    ASSERT_TRUE(reading.has_value()) << c.what;
    const Image cpu = Composite({f}, identity, false);
    std::size_t usable = 0;
    for (std::size_t i = 0; i < cpu.pixels.size() / 3; ++i) {
      const double l = 0.2126 * cpu.pixels[3 * i] + 0.7152 * cpu.pixels[3 * i + 1] + 0.0722 * cpu.pixels[3 * i + 2];
      if (std::isfinite(l) && l > 0.0) ++usable;
    }
    for (const Metering m : {Metering::kAdaptive, Metering::kCamera}) {
      const double expected = AutoExposureEv100(cpu, m);
      const double got = MeteredEv100(reading->log2_average, m);
      std::printf("%s, %s: EV100 GPU %.4f, CPU %.4f, difference %.2g stops, %u pixels\n", c.what,
                  m == Metering::kAdaptive ? "adaptive" : "camera", got, expected, got - expected, reading->pixels);
      EXPECT_NEAR(got, expected, kBinningBound) << c.what;
    }
    EXPECT_EQ(reading->pixels, usable) << c.what;
  }
}

TEST(GlExposureMeter, LeavesOutTexelsOutsideAndSumsBatchesWithTheirWeights) {
  ATMO_REQUIRE_GL_CONTEXT(context);
  context.MakeCurrent();
  ExposureMeter meter;
  // Two batches (six channels) with weights that mix them, as a spectral frame's.
  const std::vector<Frame> batches = {SkyLike(128, 96, 8.0, 6.0, 0.01, true, 1),
                                      SkyLike(128, 96, 9.0, 6.0, 0.0, true, 2)};
  const std::vector<glm::mat3> weights = {glm::mat3(0.5f, 0.1f, 0.0f, 0.2f, 0.6f, 0.1f, 0.0f, 0.1f, 0.4f),
                                          glm::mat3(0.3f, 0.0f, 0.05f, 0.1f, 0.3f, 0.1f, 0.0f, 0.0f, 0.5f)};
  const GpuTexture a = Texture(128, 96, batches[0].rgba);
  const GpuTexture b = Texture(128, 96, batches[1].rgba);
  const GpuTexture* frames[] = {&a, &b};
  meter.Meter(frames, weights, true);
  const std::optional<ExposureMeter::Reading> reading = meter.Latest(true);
  ASSERT_TRUE(reading.has_value());
  const double expected = AutoExposureEv100(Composite(batches, weights, true));
  const double got = MeteredEv100(reading->log2_average);
  std::printf("two batches, left half outside: EV100 GPU %.4f, CPU %.4f, %u pixels\n", got, expected, reading->pixels);
  EXPECT_NEAR(got, expected, kBinningBound);
  EXPECT_LE(reading->pixels, 128u * 96u / 2u);  // the left half is outside
  // Without alpha the 1e30 texels count, and the reading moves by many stops.
  meter.Meter(frames, weights, false);
  const std::optional<ExposureMeter::Reading> all = meter.Latest(true);
  ASSERT_TRUE(all.has_value());
  EXPECT_GT(all->pixels, reading->pixels);
  EXPECT_GT(all->log2_average - reading->log2_average, 10.0);
}

TEST(GlExposureMeter, ReadsTheNewestResultWithoutWaitingForIt) {
  ATMO_REQUIRE_GL_CONTEXT(context);
  context.MakeCurrent();
  ExposureMeter meter;
  const std::vector<glm::mat3> identity = {glm::mat3(1.0f)};
  EXPECT_FALSE(meter.Latest(false).has_value());  // nothing metered yet
  std::vector<GpuTexture> textures;
  for (int i = 0; i < 5; ++i) {
    // Uniform frames of 2^i: the log-average is i.
    const std::vector<float> rgba(64 * 32 * 4, static_cast<float>(std::exp2(i)));
    textures.push_back(Texture(64, 32, rgba));
    const GpuTexture* frames[] = {&textures.back()};
    meter.Meter(frames, identity, false);
    const std::optional<ExposureMeter::Reading> seen = meter.Latest(false);
    if (seen) {
      // Whatever arrived is one of the frames metered so far, at its own level.
      EXPECT_LE(seen->generation, i + 1);
      EXPECT_NEAR(seen->log2_average, seen->generation - 1, kBinningBound);
    }
  }
  const std::optional<ExposureMeter::Reading> last = meter.Latest(true);
  ASSERT_TRUE(last.has_value());
  EXPECT_EQ(last->generation, 5);
  EXPECT_NEAR(last->log2_average, 4.0, kBinningBound);
  EXPECT_EQ(last->pixels, 64u * 32u);
  // A frame with no usable pixel reads 0 pixels (AutoExposureEv100 then gives EV100 0).
  const GpuTexture black = Texture(8, 8, std::vector<float>(8 * 8 * 4, 0.0f));
  const GpuTexture* frames[] = {&black};
  meter.Meter(frames, identity, false);
  EXPECT_EQ(meter.Latest(true)->pixels, 0u);
}

TEST(GlExposureMeter, RefusesWhatItCannotMeter) {
  ATMO_REQUIRE_GL_CONTEXT(context);
  context.MakeCurrent();
  ExposureMeter meter;
  const GpuTexture a = GpuTexture::Make2D({8, 8});
  const GpuTexture b = GpuTexture::Make2D({8, 4});
  const std::vector<glm::mat3> weights(9, glm::mat3(1.0f));
  EXPECT_THROW(meter.Meter({}, weights, false), Error);
  const GpuTexture* different[] = {&a, &b};
  EXPECT_THROW(meter.Meter(different, weights, false), Error);
  std::vector<const GpuTexture*> nine(9, &a);
  EXPECT_THROW(meter.Meter(nine, weights, false), Error);
}

// A dispatch worth timing: a 256 x 256 frame cleared by a compute pass.
void SomeWork() {
  const GpuTexture target = GpuTexture::Make2D({256, 256});
  const float zero[4] = {0.0f, 0.0f, 0.0f, 0.0f};
  glClearTexImage(target.id(), 0, GL_RGBA, GL_FLOAT, zero);
}

TEST(GlTimerQueries, AreReadWhenReadyAndDeletedWhenDropped) {
  ATMO_REQUIRE_GL_CONTEXT(context);
  context.MakeCurrent();
  const std::shared_ptr<TimerQueries> queries = CurrentTimerQueries();
  ASSERT_NE(queries, nullptr);
  const std::size_t before = queries->outstanding();
  PassTimings timings;
  {
    auto record = queries->Begin();
    SomeWork();
    queries->End(*record);
    timings.AddDeferred("work", [queries, record](bool wait) { return queries->Read(*record, wait); });
  }
  EXPECT_EQ(queries->outstanding(), before + 1);
  EXPECT_GE(timings.LastMs("work"), 0.0);  // waits; a time was read (an unread pass gives -1)
  EXPECT_EQ(timings.entries()[0].calls, 1);
  EXPECT_EQ(queries->outstanding(), before);
  // A record dropped unread is deleted at the next Begin.
  { auto dropped = queries->Begin(); }
  auto next = queries->Begin();
  EXPECT_EQ(queries->outstanding(), before + 1);  // `next` alone
  queries->End(*next);
  EXPECT_TRUE(queries->Read(*next, true).has_value());
}

TEST(GlTimerQueries, TimesStillUnreadWhenTheContextEndsAreKept) {
  ATMO_REQUIRE_GL_CONTEXT(context);
  PassTimings timings;
  {
    const Context own;  // current from here
    const std::shared_ptr<TimerQueries> queries = CurrentTimerQueries();
    ASSERT_NE(queries, nullptr);
    auto record = queries->Begin();
    SomeWork();
    queries->End(*record);
    timings.AddDeferred("work", [queries, record](bool wait) { return queries->Read(*record, wait); });
  }
  context.MakeCurrent();
  EXPECT_GE(timings.LastMs("work"), 0.0);  // read by the context's end
  EXPECT_EQ(timings.entries()[0].calls, 1);
}

TEST(GlTimerQueries, GpuPassTimerNeverLosesAPass) {
  ATMO_REQUIRE_GL_CONTEXT(context);
  context.MakeCurrent();
  PassTimings timings;
  {
    GpuPassTimer timer(&timings);
    SomeWork();
    timer.Stop("first");
    SomeWork();
    SomeWork();
    timer.Stop("second");
  }
  const std::vector<PassTiming>& e = timings.entries();
  ASSERT_EQ(e.size(), 2u);
  EXPECT_EQ(e[0].name, "first");
  EXPECT_EQ(e[1].name, "second");
  for (const PassTiming& p : e) {
    EXPECT_EQ(p.calls, 1) << p.name;
    EXPECT_GE(p.last_ms, 0.0) << p.name;
  }
}

}  // namespace
}  // namespace atmo::gl
