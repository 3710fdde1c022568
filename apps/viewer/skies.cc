// The models of atmo-viewer on the GL backend (skies.h).
#include "skies.h"

#include <epoxy/gl.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <deque>
#include <map>
#include <memory>
#include <mutex>
#include <string>
#include <thread>
#include <utility>
#include <vector>

#include <oneapi/tbb/task_arena.h>

#include "atmo/error.h"
#include "cpu/camera.h"
#include "cpu/source4d_tables.h"
#include "cpu/sun_disc.h"
#include "gl/elek_gl.h"
#include "gl/hillaire_gl.h"
#include "gl/simple_gl.h"
#include "gl/source4d_gl.h"
#include "gl/timer_queries.h"
#include "models/reference_model.h"
#include "models/simple_model.h"
#include "physics/shared_parameters.h"

namespace atmo::viewer {

namespace {

using Clock = std::chrono::steady_clock;

double MillisecondsSince(Clock::time_point start) {
  return std::chrono::duration<double, std::milli>(Clock::now() - start).count();
}

std::string FrameName(const shared::CameraParameters& camera) {
  return "frame_" + std::to_string(camera.width) + "x" + std::to_string(camera.height);
}

// One frame texture per batch at the camera's size (made again when the size changed).
void SizeFrames(std::vector<gl::GpuTexture>& frames, std::size_t batches, const shared::CameraParameters& camera) {
  frames.resize(batches);
  for (gl::GpuTexture& frame : frames) {
    if (frame.empty() || frame.size2() != shared::ivec2(camera.width, camera.height)) {
      frame = gl::GpuTexture::Make2D({camera.width, camera.height});
    }
  }
}

// The batches' frames read back into one image, one channel per wavelength (as
// gl::HillaireGl::ReadFrame), with alpha for a fisheye.
Image ReadFrames(const std::vector<gl::GpuTexture>& frames, std::size_t channels, bool has_alpha) {
  if (frames.empty() || frames.front().empty()) throw Error("atmo-viewer: no frame rendered yet");
  const shared::ivec2 size = frames.front().size2();
  const std::size_t n = static_cast<std::size_t>(size.x) * size.y;
  Image image(size.x, size.y, static_cast<int>(channels));
  if (has_alpha) image.alpha.assign(n, 0.0f);
  for (std::size_t b = 0; b < frames.size(); ++b) {
    const std::vector<float> rgba = frames[b].DownloadRgba();
    for (std::size_t i = 0; i < n; ++i) {
      for (std::size_t c = 0; c < 3 && 3 * b + c < channels; ++c)
        image.pixels[channels * i + 3 * b + c] = rgba[4 * i + c];
      if (has_alpha && b == 0) image.alpha[i] = rgba[4 * i + 3];
    }
  }
  return image;
}

// How many steps of a stepped table build fit in a frame's budget. On a software GL (llvmpipe
// runs a dispatch inside the call) the wall clock measures each step as it runs. On a GPU the
// dispatches return at once, so the wall clock would queue the whole build into one frame: there
// each step is timed by GPU timer queries (gl/timer_queries.h) read without waiting when they are
// ready, a frame or more later, and kept as a running mean per kind of step (the builder's
// next_step_kind: a gather step and a convolve step differ by 50x). A frame issues steps while
// their means fit in the budget and the CPU's time spent issuing them does too (hundreds of
// cheap steps cost the CPU more than the GPU: on an H200 a 4 ms budget gave 12 ms frames before
// this bound), at least one, and at most one of a kind not timed yet (the first step of a new
// pass costs what it costs; the next frame knows).
class StepBudget {
 public:
  explicit StepBudget(const gl::Context& context) : software_(context.software_renderer()) {}

  // Runs `step()` while `more()`, for about `budget_ms` of this frame; `kind()` names the next step.
  template <typename Step, typename More, typename Kind>
  void Run(double budget_ms, const Step& step, const More& more, const Kind& kind) {
    if (software_) {
      const auto start = Clock::now();
      while (more()) {
        step();
        if (MillisecondsSince(start) >= budget_ms) break;
      }
      return;
    }
    ReadReady();
    const std::shared_ptr<gl::TimerQueries> queries = gl::CurrentTimerQueries();
    const auto start = Clock::now();
    double planned_ms = 0.0;
    bool probed = false;
    for (int i = 0; i < kMaxSteps && more(); ++i) {
      if (i > 0 && MillisecondsSince(start) >= budget_ms) break;
      std::string next = kind();
      const auto known = mean_ms_.find(next);
      if (known == mean_ms_.end()) {
        if (probed) break;
        probed = true;
      } else {
        if (i > 0 && planned_ms + known->second > budget_ms) break;
        planned_ms += known->second;
      }
      if (queries == nullptr) {
        step();
        continue;
      }
      const std::shared_ptr<gl::GpuTimeRecord> record = queries->Begin();
      step();
      queries->End(*record);
      pending_.push_back({std::move(next), [queries, record](bool wait) { return queries->Read(*record, wait); }});
    }
  }

 private:
  static constexpr int kMaxSteps = 1024;
  void ReadReady() {
    while (!pending_.empty()) {
      const std::optional<double> ms = pending_.front().read(false);
      if (!ms) break;
      // A running mean over ~4 steps of the kind (the last step of a pass may be partial).
      const auto [entry, added] = mean_ms_.emplace(pending_.front().kind, *ms);
      if (!added) entry->second = 0.75 * entry->second + 0.25 * *ms;
      pending_.pop_front();
    }
  }

  struct Pending {
    std::string kind;
    PassTimings::DeferredMs read;
  };
  bool software_;
  std::deque<Pending> pending_;
  std::map<std::string, double> mean_ms_;  // GPU ms per step, by kind
};

// The stepped table build of elek and source4d: per batch a builder (made by make_builder(b)
// when the batch before is done) stepped for `budget_ms` of this frame (StepBudget), its tables
// appended to `tables`. True once every batch's tables are built.
template <typename Builder, typename Tables, typename MakeBuilder>
bool StepBuilders(std::unique_ptr<Builder>& builder, std::vector<Tables>& tables, std::size_t batches,
                  double budget_ms, PassTimings* timings, StepBudget& budget, const MakeBuilder& make_builder) {
  const auto ensure = [&] {
    if (builder == nullptr) builder = make_builder(tables.size());
  };
  budget.Run(
      budget_ms,
      [&] {
        ensure();
        builder->Step(timings);
        if (builder->done()) {
          tables.push_back(builder->Take());
          builder.reset();
        }
      },
      [&] { return tables.size() < batches; },
      [&] {
        ensure();
        return builder->next_step_kind();
      });
  return tables.size() == batches;
}

// Batches built, and the part of the one being built, over all batches: 0 .. 1.
template <typename Builder>
double BuildProgress(const std::unique_ptr<Builder>& builder, std::size_t built, std::size_t batches) {
  const double partial = builder != nullptr ? builder->progress() : 0.0;
  return (static_cast<double>(built) + partial) / static_cast<double>(batches);
}

// A screenshot as `atmo render --backend gl` makes it for a model whose frame pass draws no disc:
// the frame without it, read back, and the disc integrated over the pixels on the host from each
// batch's transmittance table (tables[b].transmittance).
template <typename SkyType, typename Tables>
Image ScreenshotWithHostDisc(SkyType& sky, const std::vector<Tables>& tables, const AtmosphereParameters& parameters,
                             const RenderSettings& render) {
  RadianceTerms terms = render.terms;
  terms.sun_disc = false;
  sky.RenderFrame(render.camera, terms, nullptr);
  Image image = sky.ReadFrame();
  if (render.terms.sun_disc) {
    std::vector<shared::Texture2D> transmittance;
    for (const Tables& t : tables) transmittance.push_back(t.transmittance.Download2D());
    gl::AddSunDiscOnHost(parameters, transmittance, render, image);
  }
  return image;
}

class HillaireSky final : public Sky {
 public:
  HillaireSky(const gl::Context& context, const SkyRequest& request)
      : parameters_(request.parameters), sky_(context, request.parameters, request.hillaire) {}
  std::size_t batch_count() const override { return sky_.batch_count(); }
  bool Build(double, PassTimings* timings) override {
    if (!built_) sky_.Precompute(timings);
    built_ = true;
    return true;
  }
  void Recompute(PassTimings* timings) override { sky_.Precompute(timings); }
  void SetView(double altitude_m, double elevation_deg, double azimuth_deg, bool ground,
               PassTimings* timings) override {
    sky_.SetView(altitude_m, SunDirection(elevation_deg, azimuth_deg), ground, timings);
  }
  void RenderFrame(const Camera& camera, const RadianceTerms& terms, PassTimings* timings) override {
    sky_.RenderFrame(ToSharedCamera(camera), terms, timings);
  }
  const gl::GpuTexture& frame_texture(std::size_t batch) const override { return sky_.frame_texture(batch); }
  Image ReadFrame() const override { return sky_.ReadFrame(); }
  const gl::HillaireGl* hillaire_gl() const override { return &sky_; }
  // As `atmo render --backend gl` (gl::RenderHillaireGl): the frame pass without the disc, read
  // back, the disc integrated over the pixels on the host.
  Image Screenshot(const RenderSettings& render, Image*, std::uint64_t*) override {
    RadianceTerms terms = render.terms;
    terms.sun_disc = false;
    sky_.RenderFrame(ToSharedCamera(render.camera), terms);
    Image image = sky_.ReadFrame();
    if (render.terms.sun_disc) {
      std::vector<shared::Texture2D> transmittance;
      for (std::size_t b = 0; b < sky_.batch_count(); ++b) transmittance.push_back(sky_.ReadTransmittance(b));
      gl::AddSunDiscOnHost(parameters_, transmittance, render, image);
    }
    return image;
  }

 private:
  AtmosphereParameters parameters_;
  gl::HillaireGl sky_;
  bool built_ = false;
};

// Rows of work groups per builder step: 4 texel rows of a 3D table (1/64 of the default 256),
// ~30 ms of the default scattering pass on llvmpipe with 2 threads.
constexpr int kElekRowsPerStep = 1;

class ElekSky final : public Sky {
 public:
  ElekSky(const gl::Context& context, const SkyRequest& request)
      : context_(context), parameters_(request.parameters), settings_(request.elek), model_(parameters_, settings_) {
    if (!settings_.table.empty()) throw Error("atmo-viewer computes elek's table; option table= is for atmo render");
    for (std::size_t b = 0; b < model_.batches().size(); ++b) km_.push_back(gl::ElekKmAtmosphere(model_, b));
    // The settings are checked now, not in the first frame.
    builder_ = std::make_unique<gl::ElekTablesBuilder>(context_, km_[0], settings_, kElekRowsPerStep);
  }
  std::size_t batch_count() const override { return km_.size(); }
  bool Build(double budget_ms, PassTimings* timings) override {
    return StepBuilders(builder_, tables_, km_.size(), budget_ms, timings, budget_, [this](std::size_t b) {
      return std::make_unique<gl::ElekTablesBuilder>(context_, km_[b], settings_, kElekRowsPerStep);
    });
  }
  double progress() const override { return BuildProgress(builder_, tables_.size(), km_.size()); }
  void Recompute(PassTimings* timings) override {
    builder_.reset();
    tables_.clear();
    for (const shared::AtmosphereParameters& km : km_)
      tables_.push_back(gl::ComputeElekTablesGl(context_, km, settings_, timings));
  }
  void SetView(double altitude_m, double elevation_deg, double azimuth_deg, bool, PassTimings*) override {
    if (!std::isfinite(altitude_m) || altitude_m < 0.0) throw Error("altitude_m must be >= 0 for model elek");
    r_km_ = (parameters_.ground_radius_m + altitude_m) / 1000.0;
    sun_ = glm::normalize(SunDirection(elevation_deg, azimuth_deg));
  }
  void RenderFrame(const Camera& camera, const RadianceTerms& terms, PassTimings* timings) override {
    const shared::CameraParameters shared_camera = ToSharedCamera(camera);
    SizeFrames(frames_, km_.size(), shared_camera);
    has_alpha_ = camera.kind == CameraKind::kFisheye;
    gl::GpuPassTimer timer(timings);
    for (std::size_t b = 0; b < km_.size(); ++b) {
      gl::RunElekFramePass(context_, km_[b], settings_, tables_.at(b), shared_camera, r_km_, sun_, terms.sun_disc,
                           BatchValues(parameters_.solar_irradiance, b), frames_[b]);
    }
    timer.Stop(FrameName(shared_camera));
  }
  const gl::GpuTexture& frame_texture(std::size_t batch) const override { return frames_.at(batch); }
  Image ReadFrame() const override { return ReadFrames(frames_, parameters_.channel_count(), has_alpha_); }
  // As `atmo render --backend gl --model elek` (gl::RenderElekGl).
  Image Screenshot(const RenderSettings& render, Image*, std::uint64_t*) override {
    return ScreenshotWithHostDisc(*this, tables_, parameters_, render);
  }

 private:
  const gl::Context& context_;
  StepBudget budget_{context_};  // the steps of Build per frame
  AtmosphereParameters parameters_;
  ElekSettings settings_;
  ElekModel model_;  // checks the parameters; its batches' km atmospheres
  std::vector<shared::AtmosphereParameters> km_;
  std::unique_ptr<gl::ElekTablesBuilder> builder_;  // of batch tables_.size()
  std::vector<gl::ElekTablesGl> tables_;
  std::vector<gl::GpuTexture> frames_;
  double r_km_ = 6360.0;
  glm::dvec3 sun_{0.0, 0.0, 1.0};
  bool has_alpha_ = false;
};

// Work groups (64 invocations) per source4d builder step: a few ms of the default gathering
// (64 steps of 24 samples per invocation) on llvmpipe with 2 threads.
constexpr int kSource4dGroupsPerStep = 16;

// The CPU's build of source4d's tables (cpu::ComputeSource4dTables, what Source4dModel::Precompute
// runs) on a thread of its own, for --source4d-tables cpu: on a software GL (llvmpipe) the CPU
// backend builds them ~8x faster than the GL passes (docs/performance.md, "source4d beside
// hillaire"). The build runs in a oneTBB arena of its own, so that a parallel loop of the render
// thread never picks up one of its tasks (work stealing within one arena) and stalls a frame.
// The build reports each finished pass (transmittance, quadrature, gathering and product per
// order, sum: 2 x orders + 1 per batch) and checks `cancel` there: a cancelled build stops after
// the pass it is in. Its threads keep the render thread's priority: at 1280x720 llvmpipe's frames
// keep both cores of a 2-core machine busy, and a build at nice 10 took 24 s instead of 5 s to
// reach the screen (docs/viewer.md).
struct Source4dCpuBuildState {
  std::atomic<bool> cancel{false};
  std::atomic<bool> finished{false};
  std::atomic<int> passes_done{0};
  int passes_total = 0;
  mutable std::mutex mutex;  // guards what follows
  std::vector<std::pair<std::string, double>> passes;  // name and ms of each finished pass, in order
  std::vector<cpu::Source4dTables> tables;             // per batch, once finished without an error
  std::string error;                                   // what the build threw, else empty
};

struct Source4dBuildCancelled {};

void RunSource4dCpuBuild(const std::shared_ptr<Source4dCpuBuildState>& state,
                         const std::vector<shared::AtmosphereParameters>& atmospheres,
                         const cpu::Source4dSettings& settings) {
  try {
    oneapi::tbb::task_arena arena;
    arena.execute([&] {
      if (state->cancel) throw Source4dBuildCancelled{};
      std::vector<cpu::Source4dTables> built(atmospheres.size());
      std::vector<cpu::Source4dTables*> tables;
      for (cpu::Source4dTables& t : built) tables.push_back(&t);
      cpu::ComputeSource4dTables(atmospheres, settings, tables, [&](std::string_view pass, double ms) {
        {
          std::lock_guard<std::mutex> lock(state->mutex);
          state->passes.emplace_back(std::string(pass), ms);
        }
        ++state->passes_done;
        if (state->cancel) throw Source4dBuildCancelled{};
      });
      std::lock_guard<std::mutex> lock(state->mutex);
      state->tables = std::move(built);
    });
  } catch (const Source4dBuildCancelled&) {
  } catch (const std::exception& error) {
    std::lock_guard<std::mutex> lock(state->mutex);
    state->error = error.what();
  }
  state->finished = true;
}

// The builds of skies destroyed while their build ran (a parameter changed again): cancelled,
// left to stop after their current pass, joined once finished (never waited for, but at exit).
class RetiredSource4dBuilds {
 public:
  ~RetiredSource4dBuilds() { JoinAll(); }
  void Retire(std::shared_ptr<Source4dCpuBuildState> state, std::thread thread) {
    std::lock_guard<std::mutex> lock(mutex_);
    JoinFinished();
    builds_.emplace_back(std::move(state), std::move(thread));
  }
  void JoinAll() {
    std::lock_guard<std::mutex> lock(mutex_);
    for (auto& [state, thread] : builds_) {
      if (thread.joinable()) thread.join();
    }
    builds_.clear();
  }

 private:
  void JoinFinished() {
    std::erase_if(builds_, [](auto& build) {
      if (!build.first->finished) return false;
      build.second.join();  // its last statement ran: returns at once
      return true;
    });
  }
  std::mutex mutex_;
  std::vector<std::pair<std::shared_ptr<Source4dCpuBuildState>, std::thread>> builds_;
};

RetiredSource4dBuilds& RetiredBuilds() {
  static RetiredSource4dBuilds builds;
  return builds;
}

// One build of every batch's tables on a worker thread; destroyed before it finished, it is
// cancelled and retired (RetiredSource4dBuilds), not waited for.
class Source4dCpuBuild {
 public:
  Source4dCpuBuild(std::vector<shared::AtmosphereParameters> atmospheres, const cpu::Source4dSettings& settings)
      : state_(std::make_shared<Source4dCpuBuildState>()) {
    // ComputeSource4dTables's passes, each over all batches: transmittance, quadrature, sum, and
    // with orders >= 2 the gathering of orders 1 .. N-1 and the products of orders 2 .. N.
    state_->passes_total = 2 * std::max(settings.orders, 1) + 1;
    thread_ = std::thread([state = state_, atmospheres = std::move(atmospheres), settings] {
      RunSource4dCpuBuild(state, atmospheres, settings);
    });
  }
  ~Source4dCpuBuild() {
    if (!thread_.joinable()) return;  // taken
    state_->cancel = true;
    if (state_->finished) {
      thread_.join();
    } else {
      RetiredBuilds().Retire(state_, std::move(thread_));
    }
  }
  Source4dCpuBuild(const Source4dCpuBuild&) = delete;
  Source4dCpuBuild& operator=(const Source4dCpuBuild&) = delete;

  bool finished() const { return state_->finished; }
  // Passes finished / passes in all: 0 .. 1, by pass, not by time (the gatherings take most).
  double progress() const {
    return std::min(1.0, static_cast<double>(state_->passes_done) / std::max(state_->passes_total, 1));
  }
  std::string Status() const {
    std::lock_guard<std::mutex> lock(state_->mutex);
    std::string line = "tables on the CPU: " + std::to_string(state_->passes.size()) + " of " +
                       std::to_string(state_->passes_total) + " passes";
    if (!state_->passes.empty()) line += " (last " + state_->passes.back().first + ")";
    return line;
  }
  // The CPU's pass times so far, as cpu_NAME (each name once per batch).
  void AddPassTimes(PassTimings* timings) const {
    if (timings == nullptr) return;
    std::lock_guard<std::mutex> lock(state_->mutex);
    for (const auto& [name, ms] : state_->passes) timings->Add("cpu_" + name, ms);
  }
  // Once finished(): the tables per batch; throws atmo::Error with what the build threw.
  std::vector<cpu::Source4dTables> Take() {
    thread_.join();
    std::lock_guard<std::mutex> lock(state_->mutex);
    if (!state_->error.empty()) throw Error(state_->error);
    return std::move(state_->tables);
  }

 private:
  std::shared_ptr<Source4dCpuBuildState> state_;
  std::thread thread_;
};

// Source4d: its tables either per batch from a gl::Source4dTablesBuilder run a few steps per
// frame (as elek's; request.source4d_cpu_tables false), or from the CPU on a worker thread
// (Source4dCpuBuild), uploaded once all are built; then RunSource4dFramePass, the passes of
// `atmo render --backend gl --model source4d` (gl::RenderSource4dGl of the CPU-built model with
// CPU tables).
class Source4dSky final : public Sky {
 public:
  Source4dSky(const gl::Context& context, const SkyRequest& request)
      : context_(context),
        parameters_(request.parameters),
        model_(parameters_, request.source4d),
        cpu_tables_(request.source4d_cpu_tables) {
    for (std::size_t b = 0; b < model_.batches().size(); ++b) km_.push_back(ToSharedParameters(parameters_, b, 1000.0));
    if (cpu_tables_) {
      cpu_build_ = std::make_unique<Source4dCpuBuild>(CpuAtmospheres(), model_.settings().tables);
      return;
    }
    // The settings are checked (and the programs compiled) now, not in the first frame.
    builder_ = std::make_unique<gl::Source4dTablesBuilder>(context_, km_[0], model_.settings().tables,
                                                           kSource4dGroupsPerStep);
  }
  std::size_t batch_count() const override { return km_.size(); }
  bool Build(double budget_ms, PassTimings* timings) override {
    if (cpu_tables_) {
      if (cpu_build_ == nullptr) return true;
      cpu_build_->AddPassTimes(timings);
      if (!cpu_build_->finished()) return false;  // the last sky stays on screen
      const std::vector<cpu::Source4dTables> tables = cpu_build_->Take();
      cpu_build_.reset();
      Upload(tables, timings);
      return true;
    }
    const std::size_t built = tables_.size();
    const bool done = StepBuilders(builder_, tables_, km_.size(), budget_ms, timings, budget_, [this](std::size_t b) {
      return std::make_unique<gl::Source4dTablesBuilder>(context_, km_[b], model_.settings().tables,
                                                         kSource4dGroupsPerStep);
    });
    if (tables_.size() != built) sky_view_stale_ = true;
    return done;
  }
  double progress() const override {
    if (cpu_tables_) return cpu_build_ != nullptr ? cpu_build_->progress() : 1.0;
    return BuildProgress(builder_, tables_.size(), km_.size());
  }
  bool BuildsOnItsOwnThread() const override { return cpu_build_ != nullptr; }
  std::string BuildStatus() const override {
    return cpu_build_ != nullptr ? cpu_build_->Status() : (cpu_tables_ ? "" : "tables on the GPU");
  }
  void Recompute(PassTimings* timings) override {
    builder_.reset();
    cpu_build_.reset();
    if (cpu_tables_) {
      // On this thread, at once (the benchmark of --recompute-every-frame).
      const std::vector<shared::AtmosphereParameters> atmospheres = CpuAtmospheres();
      std::vector<cpu::Source4dTables> tables(atmospheres.size());
      std::vector<cpu::Source4dTables*> pointers;
      for (cpu::Source4dTables& t : tables) pointers.push_back(&t);
      cpu::ComputeSource4dTables(atmospheres, model_.settings().tables, pointers,
                                 [&](std::string_view pass, double ms) {
                                   if (timings != nullptr) timings->Add("cpu_" + std::string(pass), ms);
                                 });
      Upload(tables, timings);
      return;
    }
    tables_.clear();
    for (const shared::AtmosphereParameters& km : km_)
      tables_.push_back(gl::ComputeSource4dTablesGl(context_, km, model_.settings().tables, timings));
    sky_view_stale_ = true;
  }
  void SetView(double altitude_m, double elevation_deg, double azimuth_deg, bool, PassTimings*) override {
    const glm::dvec3 sun = glm::normalize(SunDirection(elevation_deg, azimuth_deg));
    model_.View(altitude_m, sun);  // what the CPU model refuses (below the ground), as atmo render
    if (r_km_ != (parameters_.ground_radius_m + altitude_m) / 1000.0 || sun_ != sun) sky_view_stale_ = true;
    r_km_ = (parameters_.ground_radius_m + altitude_m) / 1000.0;
    sun_ = sun;
  }
  void RenderFrame(const Camera& camera, const RadianceTerms& terms, PassTimings* timings) override {
    const shared::CameraParameters shared_camera = ToSharedCamera(camera);
    SizeFrames(frames_, km_.size(), shared_camera);
    has_alpha_ = camera.kind == CameraKind::kFisheye;
    // The sky-view tables (inside the atmosphere), remade when the observer, the sun or the
    // tables change: the frame pass then reads them instead of marching every pixel.
    const bool use_sky_view = gl::Source4dSkyViewServes(model_.settings(), km_[0], r_km_);
    if (use_sky_view && (sky_view_stale_ || sky_views_.size() != km_.size())) {
      sky_views_.resize(km_.size());
      gl::GpuPassTimer sky_view_timer(timings);
      for (std::size_t b = 0; b < km_.size(); ++b) {
        gl::RunSource4dSkyViewPass(context_, km_[b], tables_.at(b), model_.settings().samples,
                                   model_.settings().sky_view_lut, r_km_, sun_, sky_views_[b]);
      }
      sky_view_timer.Stop("sky_view_lut");
      sky_view_stale_ = false;
    }
    gl::GpuPassTimer timer(timings);
    for (std::size_t b = 0; b < km_.size(); ++b) {
      gl::RunSource4dFramePass(context_, km_[b], tables_.at(b), model_.settings().samples, shared_camera, r_km_, sun_,
                               terms.ground, terms.sun_disc, BatchValues(parameters_.solar_irradiance, b),
                               frames_[b], use_sky_view ? &sky_views_[b] : nullptr);
    }
    timer.Stop(FrameName(shared_camera));
  }
  const gl::GpuTexture& frame_texture(std::size_t batch) const override { return frames_.at(batch); }
  Image ReadFrame() const override { return ReadFrames(frames_, parameters_.channel_count(), has_alpha_); }
  // As `atmo render --backend gl --model source4d` (gl::RenderSource4dGl).
  Image Screenshot(const RenderSettings& render, Image*, std::uint64_t*) override {
    return ScreenshotWithHostDisc(*this, tables_, parameters_, render);
  }

 private:
  // The batches' atmospheres in metres, as Source4dModel::Precompute builds them.
  std::vector<shared::AtmosphereParameters> CpuAtmospheres() const {
    std::vector<shared::AtmosphereParameters> atmospheres;
    for (const Source4dModel::Batch& batch : model_.batches()) atmospheres.push_back(batch.atmosphere);
    return atmospheres;
  }
  void Upload(const std::vector<cpu::Source4dTables>& tables, PassTimings* timings) {
    const auto start = Clock::now();
    tables_.clear();
    for (const cpu::Source4dTables& t : tables) tables_.push_back(gl::UploadSource4dTables(t));
    if (timings != nullptr) timings->Add("source4d_gl_upload", MillisecondsSince(start));
    sky_view_stale_ = true;
  }

  const gl::Context& context_;
  StepBudget budget_{context_};  // the steps of Build per frame (GPU tables)
  AtmosphereParameters parameters_;
  Source4dModel model_;  // checks the parameters and the settings; no tables of its own
  std::vector<shared::AtmosphereParameters> km_;
  bool cpu_tables_ = false;                             // the tables from the CPU (Source4dCpuBuild)
  std::unique_ptr<gl::Source4dTablesBuilder> builder_;  // GPU: of batch tables_.size()
  std::unique_ptr<Source4dCpuBuild> cpu_build_;          // CPU: every batch, until uploaded
  std::vector<gl::Source4dTablesGl> tables_;
  std::vector<gl::GpuTexture> frames_;
  std::vector<gl::Source4dSkyViewGl> sky_views_;  // per batch, for r_km_ and sun_
  bool sky_view_stale_ = true;
  double r_km_ = 6360.0;
  glm::dvec3 sun_{0.0, 0.0, 1.0};
  bool has_alpha_ = false;
};

class SimpleSky final : public Sky {
 public:
  SimpleSky(const gl::Context& context, const SkyRequest& request)
      : context_(context), parameters_(request.parameters), model_(parameters_, {}) {}
  std::size_t batch_count() const override { return model_.batches().size(); }
  bool Build(double, PassTimings*) override { return true; }
  void Recompute(PassTimings*) override {}
  void SetView(double altitude_m, double elevation_deg, double azimuth_deg, bool, PassTimings*) override {
    if (!std::isfinite(altitude_m)) throw Error("altitude_m must be finite for model simple");
    altitude_m_ = altitude_m;
    sun_ = glm::normalize(SunDirection(elevation_deg, azimuth_deg));
  }
  void RenderFrame(const Camera& camera, const RadianceTerms& terms, PassTimings* timings) override {
    const shared::CameraParameters shared_camera = ToSharedCamera(camera);
    SizeFrames(frames_, batch_count(), shared_camera);
    has_alpha_ = camera.kind == CameraKind::kFisheye;
    gl::GpuPassTimer timer(timings);
    for (std::size_t b = 0; b < batch_count(); ++b) {
      gl::RunSimpleFramePass(context_, model_.batches()[b], altitude_m_, sun_, shared_camera, terms.sun_disc,
                             BatchValues(parameters_.solar_irradiance, b), frames_[b]);
    }
    timer.Stop(FrameName(shared_camera));
  }
  const gl::GpuTexture& frame_texture(std::size_t batch) const override { return frames_.at(batch); }
  Image ReadFrame() const override { return ReadFrames(frames_, parameters_.channel_count(), has_alpha_); }
  // The GL frame without the disc, and the disc of the CPU's SkyView integrated over the pixels
  // (cpu/sun_disc.h), as atmo::RenderView adds it.
  Image Screenshot(const RenderSettings& render, Image*, std::uint64_t*) override {
    RadianceTerms terms = render.terms;
    terms.sun_disc = false;
    RenderFrame(render.camera, terms, nullptr);
    Image image = ReadFrame();
    if (render.terms.sun_disc) {
      const std::unique_ptr<SkyView> view = model_.View(altitude_m_, sun_);
      AddSunDisc(*view, render.camera, parameters_.solar_irradiance, image);
    }
    return image;
  }

 private:
  const gl::Context& context_;
  AtmosphereParameters parameters_;
  SimpleModel model_;
  std::vector<gl::GpuTexture> frames_;
  double altitude_m_ = 0.0;
  glm::dvec3 sun_{0.0, 0.0, 1.0};
  bool has_alpha_ = false;
};

// The progressive render on a background thread; each finished pass replaces the shown estimate.
class ReferenceSky final : public Sky {
 public:
  ReferenceSky(const gl::Context&, const SkyRequest& request)
      : parameters_(request.parameters),
        model_(CreateModel("reference", request.parameters, request.reference_options)),
        spp_(request.reference_spp),
        divisor_(std::max(1, request.reference_divisor)) {
    if (spp_ == 0) spp_ = static_cast<const ReferenceModel&>(*model_).settings().samples;
    if (spp_ < 2) throw Error("model reference needs at least 2 paths per pixel (--spp)");
  }
  ~ReferenceSky() override { Stop(); }
  std::size_t batch_count() const override { return ChannelBatchCount(parameters_.channel_count()); }
  bool Build(double, PassTimings*) override { return true; }
  void Recompute(PassTimings*) override {}
  void SetView(double altitude_m, double elevation_deg, double azimuth_deg, bool, PassTimings*) override {
    if (!std::isfinite(altitude_m) || altitude_m < 0.0) throw Error("altitude_m must be >= 0 for model reference");
    altitude_m_ = altitude_m;
    elevation_deg_ = elevation_deg;
    azimuth_deg_ = azimuth_deg;
  }
  void RenderFrame(const Camera& camera, const RadianceTerms& terms, PassTimings* timings) override {
    const auto start = Clock::now();
    RenderSettings wanted;
    wanted.camera = camera;
    wanted.camera.width = std::max(1, camera.width / divisor_);
    wanted.camera.height = std::max(1, camera.height / divisor_);
    wanted.terms = terms;
    wanted.altitude_m = altitude_m_;
    wanted.sun_elevation_deg = elevation_deg_;
    wanted.sun_azimuth_deg = azimuth_deg_;
    // The night sky and the moon of SetNight (a new one of either restarts the render).
    wanted.terms.night_sky = night_.get();
    wanted.terms.moon = moon_.get();
    wanted.terms.moon_sky = nullptr;
    if (!running_ || !SameRender(wanted, running_settings_)) Restart(wanted);
    Upload();
    if (timings != nullptr) timings->Add("reference_upload", MillisecondsSince(start));
  }
  const gl::GpuTexture& frame_texture(std::size_t batch) const override { return textures_.at(batch); }
  bool HasFrame() const override {
    std::lock_guard<std::mutex> lock(mutex_);
    return shown_.radiance.width > 0;
  }
  Image ReadFrame() const override {
    std::lock_guard<std::mutex> lock(mutex_);
    if (shown_.radiance.width == 0) throw Error("atmo-viewer: no reference pass finished yet");
    return shown_.radiance;
  }
  // The estimate shown (the last finished pass), at its own size, with its standard error.
  Image Screenshot(const RenderSettings&, Image* standard_error, std::uint64_t* samples_per_pixel) override {
    std::lock_guard<std::mutex> lock(mutex_);
    if (shown_.radiance.width == 0) throw Error("no reference pass finished yet: nothing to write");
    if (standard_error != nullptr) *standard_error = shown_.standard_error;
    if (samples_per_pixel != nullptr) *samples_per_pixel = shown_.samples_per_pixel;
    return shown_.radiance;
  }
  std::string Status() const override {
    std::lock_guard<std::mutex> lock(mutex_);
    if (!error_.empty()) return "reference: " + error_;
    if (shown_.radiance.width == 0) return "reference: first pass running";
    char line[200];
    std::snprintf(line, sizeof line, "reference %dx%d: %llu of %llu paths per pixel, median relative SE %.3g %%",
                  shown_.radiance.width, shown_.radiance.height,
                  static_cast<unsigned long long>(shown_.samples_per_pixel), static_cast<unsigned long long>(spp_),
                  100.0 * median_se_);
    return line;
  }
  bool Converged() const override {
    std::lock_guard<std::mutex> lock(mutex_);
    return shown_.samples_per_pixel >= spp_ || !error_.empty();
  }
  bool SameInputsSameFrame() const override { return false; }
  bool DrawsNight() const override { return true; }
  void SetNight(std::shared_ptr<const NightSky> night, std::shared_ptr<const Moon> moon) override {
    if (night != nullptr && night->channel_count() != parameters_.channel_count()) {
      night = nullptr;  // made for other channels (a compared sky's): none, as the viewer's GPU pass does
      moon = nullptr;
    }
    night_ = std::move(night);
    moon_ = std::move(moon);
  }

 private:
  static bool SameRender(const RenderSettings& a, const RenderSettings& b) {
    const Camera& p = a.camera;
    const Camera& q = b.camera;
    return p.kind == q.kind && p.width == q.width && p.height == q.height && p.fov_deg == q.fov_deg &&
           p.yaw_deg == q.yaw_deg && p.pitch_deg == q.pitch_deg && a.terms.sun_disc == b.terms.sun_disc &&
           a.terms.ground == b.terms.ground && a.altitude_m == b.altitude_m &&
           a.sun_elevation_deg == b.sun_elevation_deg && a.sun_azimuth_deg == b.sun_azimuth_deg &&
           a.terms.night_sky == b.terms.night_sky && a.terms.moon == b.terms.moon;
  }
  void Stop() {
    cancel_ = true;
    if (thread_.joinable()) thread_.join();
    cancel_ = false;
  }
  void Restart(const RenderSettings& settings) {
    Stop();
    {
      std::lock_guard<std::mutex> lock(mutex_);
      shown_ = ProgressiveImage{};
      fresh_ = false;
      error_.clear();
    }
    // Black until the first pass is done.
    textures_.clear();
    for (std::size_t b = 0; b < batch_count(); ++b) {
      textures_.push_back(gl::GpuTexture::Make2D({settings.camera.width, settings.camera.height}));
      const std::vector<float> black(4 * static_cast<std::size_t>(settings.camera.width) * settings.camera.height,
                                     0.0f);
      glTextureSubImage2D(textures_.back().id(), 0, 0, 0, settings.camera.width, settings.camera.height, GL_RGBA,
                          GL_FLOAT, black.data());
    }
    running_settings_ = settings;
    running_ = true;
    running_night_ = night_;
    running_moon_ = moon_;
    // The moon's light: this model's view for a sun in the moon's direction (as `atmo render`).
    running_moon_view_ = moon_ != nullptr ? model_->View(settings.altitude_m, moon_->direction()) : nullptr;
    running_settings_.terms.moon_sky = running_moon_view_.get();
    thread_ = std::thread([this, settings = running_settings_] {
      ProgressiveSettings progressive;
      progressive.samples_per_pixel = spp_;
      progressive.cancel = &cancel_;
      progressive.on_pass = [this](const ProgressiveImage& pass) {
        if (cancel_) return;
        const double se = MedianRelativeStandardError(pass.radiance, pass.standard_error);
        std::lock_guard<std::mutex> lock(mutex_);
        shown_ = pass;
        median_se_ = se;
        fresh_ = true;
      };
      try {
        RenderProgressive(*model_, settings, progressive);
      } catch (const std::exception& error) {
        std::lock_guard<std::mutex> lock(mutex_);
        error_ = error.what();
      }
    });
  }
  // The newest pass into the frame textures (rgba per batch of three channels).
  void Upload() {
    std::lock_guard<std::mutex> lock(mutex_);
    if (!fresh_) return;
    fresh_ = false;
    const Image& image = shown_.radiance;
    const std::size_t nc = static_cast<std::size_t>(image.channels);
    const std::size_t n = static_cast<std::size_t>(image.width) * image.height;
    std::vector<float> rgba(4 * n);
    for (std::size_t b = 0; b < textures_.size(); ++b) {
      for (std::size_t i = 0; i < n; ++i) {
        for (std::size_t c = 0; c < 3; ++c) {
          rgba[4 * i + c] = 3 * b + c < nc ? image.pixels[nc * i + 3 * b + c] : 0.0f;
        }
        rgba[4 * i + 3] = image.alpha.empty() ? 1.0f : image.alpha[i];
      }
      glTextureSubImage2D(textures_[b].id(), 0, 0, 0, image.width, image.height, GL_RGBA, GL_FLOAT, rgba.data());
    }
  }

  AtmosphereParameters parameters_;
  std::unique_ptr<Model> model_;
  std::uint64_t spp_ = 0;
  int divisor_ = 4;
  double altitude_m_ = 0.0;
  double elevation_deg_ = 90.0;
  double azimuth_deg_ = 0.0;
  std::vector<gl::GpuTexture> textures_;
  RenderSettings running_settings_;
  bool running_ = false;
  // SetNight's night sky and moon; those the running render traces (its terms point at them) and
  // the model's view for a sun in that moon's direction, kept until the next Restart.
  std::shared_ptr<const NightSky> night_;
  std::shared_ptr<const Moon> moon_;
  std::shared_ptr<const NightSky> running_night_;
  std::shared_ptr<const Moon> running_moon_;
  std::unique_ptr<SkyView> running_moon_view_;
  std::thread thread_;
  std::atomic<bool> cancel_{false};
  mutable std::mutex mutex_;  // guards what follows (the worker's results)
  ProgressiveImage shown_;
  double median_se_ = 0.0;
  bool fresh_ = false;
  std::string error_;
};

}  // namespace

void JoinSource4dCpuBuilds() { RetiredBuilds().JoinAll(); }

const std::vector<std::string>& ViewerModelNames() {
  static const std::vector<std::string> names = {"hillaire", "elek", "simple", "reference", "source4d"};
  return names;
}

std::unique_ptr<Sky> MakeSky(const gl::Context& context, const SkyRequest& request) {
  if (request.model == "hillaire") return std::make_unique<HillaireSky>(context, request);
  if (request.model == "elek") return std::make_unique<ElekSky>(context, request);
  if (request.model == "simple") return std::make_unique<SimpleSky>(context, request);
  if (request.model == "reference") return std::make_unique<ReferenceSky>(context, request);
  if (request.model == "source4d") return std::make_unique<Source4dSky>(context, request);
  throw Error("unknown model '" + request.model + "' (atmo-viewer shows hillaire, elek, simple, reference, source4d)");
}

double MedianRelativeStandardError(const Image& radiance, const Image& standard_error) {
  std::vector<double> ratios;
  ratios.reserve(radiance.pixels.size());
  for (std::size_t i = 0; i < radiance.pixels.size() && i < standard_error.pixels.size(); ++i) {
    if (radiance.pixels[i] > 0.0f) ratios.push_back(standard_error.pixels[i] / radiance.pixels[i]);
  }
  if (ratios.empty()) return 0.0;
  const auto middle = ratios.begin() + static_cast<std::ptrdiff_t>(ratios.size() / 2);
  std::nth_element(ratios.begin(), middle, ratios.end());
  return *middle;
}

}  // namespace atmo::viewer
