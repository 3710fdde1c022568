// Named pass timings: every parallel pass of atmo has a name and a timer.
//
// To use it: { ScopedPassTimer t(timings, "transmittance_lut"); ...work... }  then read
// timings.entries() (in order of first use; a pass run again accumulates calls and time).
#pragma once

#include <chrono>
#include <deque>
#include <functional>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

namespace atmo {

struct PassTiming {
  std::string name;
  double total_ms = 0.0;
  int calls = 0;
  double last_ms = 0.0;
};

class PassTimings {
 public:
  void Add(std::string_view name, double ms);
  // A pass whose time is known later (a GPU timer query, src/atmo/gl/timer_queries.h):
  // `read(wait)` gives its milliseconds, or nothing while it is not ready and `wait` is false.
  // Its entry keeps its place in entries() from now on; its time is added when collected.
  using DeferredMs = std::function<std::optional<double>(bool wait)>;
  void AddDeferred(std::string_view name, DeferredMs read);
  // Adds the deferred times that are ready, in the order they were added, stopping at the first
  // that is not (with `wait`: all of them, waiting for the GPU). True when none is left. The
  // viewer collects without waiting a frame later; entries() and LastMs() collect with waiting.
  bool Collect(bool wait) const;
  bool has_pending() const { return !pending_.empty(); }
  const std::vector<PassTiming>& entries() const {
    Collect(true);
    return entries_;
  }
  // Last duration of the named pass in milliseconds, or -1 if it never ran.
  double LastMs(std::string_view name) const;
  // Forgets every entry, and the deferred times not collected yet.
  void Clear() {
    entries_.clear();
    pending_.clear();
  }

 private:
  PassTiming& Entry(std::string_view name) const;
  static void Record(PassTiming& entry, double ms);

  struct Pending {
    std::string name;
    DeferredMs read;
  };
  mutable std::vector<PassTiming> entries_;
  mutable std::deque<Pending> pending_;
};

class ScopedPassTimer {
 public:
  ScopedPassTimer(PassTimings& timings, std::string_view name)
      : timings_(timings), name_(name), start_(std::chrono::steady_clock::now()) {}
  ~ScopedPassTimer() {
    const auto end = std::chrono::steady_clock::now();
    timings_.Add(name_, std::chrono::duration<double, std::milli>(end - start_).count());
  }
  ScopedPassTimer(const ScopedPassTimer&) = delete;
  ScopedPassTimer& operator=(const ScopedPassTimer&) = delete;

 private:
  PassTimings& timings_;
  std::string name_;
  std::chrono::steady_clock::time_point start_;
};

// Long work announced: when a model's precomputation is estimated to take at least
// `min_seconds` (Model::EstimatedPrecomputeSeconds), CreateModel sends the handler one message
// with the estimate before it starts and one as each pass ends ("source4d_gather_2 done, 41 s
// in"). The command line prints them on stderr (atmo: ...); the default handler is empty
// (silent). Messages may come from any thread, one at a time. Thread-safe.
using ProgressHandler = std::function<void(const std::string& message)>;
void SetProgressHandler(ProgressHandler handler, double min_seconds = 10.0);

// Implementation of the above for CreateModel and Model::RecordPass.
namespace progress {
bool Wanted(double estimated_seconds);
void Send(const std::string& message);
}  // namespace progress

}  // namespace atmo
