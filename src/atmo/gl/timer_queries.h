// GPU timer queries read when they are ready, not when they are issued (private to atmo::gl).
//
// A pass timed on a GPU gets two GL_TIMESTAMP queries, one before and one after its commands.
// Reading a query's result right after issuing it waits for the GPU to finish everything queued
// (a pipeline stall per timed pass); here the result is read later, by PassTimings::Collect
// (include/atmo/timing.h) when the caller next looks at the timings: a frame later in the
// viewer, after the repeat in `atmo bench`, or at once when a test reads LastMs.
//
// To use it (GpuPassTimer in resources.cc does):
//   std::shared_ptr<TimerQueries> queries = CurrentTimerQueries();  // the current Context's
//   auto record = queries->Begin();       // before the pass's commands
//   ... dispatches ...
//   queries->End(*record);                 // after them
//   timings.AddDeferred("pass", [queries, record](bool wait) { return queries->Read(*record, wait); });
//
// Each Context owns one TimerQueries, made current with it on its thread. When the context ends,
// every result still unread is read (Drain), so a PassTimings outliving its context still holds
// every time; queries whose record was dropped unread are deleted on the next Begin or at the end.
// Read needs the owning context current on the calling thread (or ended); elsewhere it answers
// nothing. Not thread-safe: one per context, used on the context's thread.
#pragma once

#include <memory>
#include <optional>
#include <vector>

namespace atmo::gl {

struct GpuTimeRecord {
  unsigned begin = 0;  // GL query names (0 once read)
  unsigned end = 0;
  bool done = false;
  double ms = 0.0;
};

class TimerQueries : public std::enable_shared_from_this<TimerQueries> {
 public:
  TimerQueries() = default;
  TimerQueries(const TimerQueries&) = delete;
  TimerQueries& operator=(const TimerQueries&) = delete;

  std::shared_ptr<GpuTimeRecord> Begin();
  void End(GpuTimeRecord& record);
  // The record's milliseconds: at once when ready (or read before); with `wait`, after waiting
  // for the GPU; otherwise nothing yet.
  std::optional<double> Read(GpuTimeRecord& record, bool wait);
  // Reads every live record (waiting for the GPU) and deletes every query: the context ends.
  void Drain();

  // Records issued, held by a reader and not read yet (for tests).
  std::size_t outstanding() const;

 private:
  void Prune();  // deletes the queries of records nobody will read
  static void Finish(GpuTimeRecord& record);

  std::vector<std::shared_ptr<GpuTimeRecord>> records_;
  bool live_ = true;
};

// The TimerQueries of the Context current on this thread (set by its constructors and
// MakeCurrent), or null when none is.
std::shared_ptr<TimerQueries> CurrentTimerQueries();
// For Context: the thread's current queries (null: none). A plain pointer: a thread_local with
// a destructor would be destroyed at the thread's exit before a static Context ends.
void SetCurrentTimerQueries(TimerQueries* queries);

}  // namespace atmo::gl
