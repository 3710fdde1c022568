// Long work announced (atmo::SetProgressHandler): the estimate before a model's precomputation
// and each pass as it ends, only above the handler's threshold.
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "atmo/model.h"
#include "atmo/parameters.h"
#include "atmo/timing.h"
#include "models/source4d_model.h"

namespace atmo {
namespace {

struct HandlerGuard {
  ~HandlerGuard() { SetProgressHandler({}); }
};

TEST(Progress, LongPrecomputationIsAnnouncedWithItsPasses) {
  const HandlerGuard guard;
  std::vector<std::string> messages;
  SetProgressHandler([&](const std::string& m) { messages.push_back(m); }, 0.0);  // every model counts as long
  CreateModel("source4d", Preset("earth"), {{"table", "8x8x24x4"}, {"orders", "2"}});
  ASSERT_GE(messages.size(), 3u);
  EXPECT_EQ(messages[0].rfind("source4d precomputation: about ", 0), 0u) << messages[0];
  EXPECT_NE(messages[0].find(" threads (an estimate)"), std::string::npos) << messages[0];
  bool gather = false;
  for (const std::string& m : messages) gather = gather || m.rfind("source4d_gather_1 done, ", 0) == 0;
  EXPECT_TRUE(gather);
  // Below the threshold nothing is said; hillaire estimates no long work at all.
  messages.clear();
  SetProgressHandler([&](const std::string& m) { messages.push_back(m); }, 1e9);
  CreateModel("source4d", Preset("earth"), {{"table", "8x8x24x4"}, {"orders", "2"}});
  SetProgressHandler([&](const std::string& m) { messages.push_back(m); }, 1e-9);
  CreateModel("hillaire", Preset("earth"));
  EXPECT_TRUE(messages.empty());
}

// The estimates follow the work: twice the cells or orders, twice the time; a second batch of
// channels adds what the batches do not share.
TEST(Progress, EstimatesScaleWithTheWork) {
  const auto estimate = [](const char* model, const AtmosphereParameters& p, const ModelOptions& o) {
    return CreateModel(model, p, o)->EstimatedPrecomputeSeconds();
  };
  const double base = estimate("source4d", Preset("earth"), {{"table", "8x8x24x4"}, {"orders", "2"}});
  EXPECT_GT(base, 0.0);
  EXPECT_NEAR(estimate("source4d", Preset("earth"), {{"table", "16x8x24x4"}, {"orders", "2"}}) / base, 2.0, 1e-12);
  EXPECT_NEAR(estimate("source4d", Preset("earth"), {{"table", "8x8x24x4"}, {"orders", "4"}}) / base, 2.0, 1e-12);
  AtmosphereParameters six = Preset("earth-spectral");
  six.wavelengths_nm.resize(6);
  for (auto* v : {&six.rayleigh.scattering_per_m, &six.rayleigh.absorption_per_m, &six.mie.scattering_per_m,
                  &six.mie.absorption_per_m, &six.ozone.scattering_per_m, &six.ozone.absorption_per_m,
                  &six.ground_albedo, &six.solar_irradiance}) {
    v->resize(6);
  }
  EXPECT_NEAR(estimate("source4d", six, {{"table", "8x8x24x4"}, {"orders", "2"}}) / base,
              1.0 + kSource4dExtraBatchCost, 1e-12);
  const double elek = estimate("elek", Preset("earth"), {{"size", "8x32x8"}, {"orders", "2"}});
  EXPECT_NEAR(estimate("elek", Preset("earth"), {{"size", "16x32x8"}, {"orders", "2"}}) / elek, 2.0, 1e-12);
}

}  // namespace
}  // namespace atmo
