#include "atmo/timing.h"

#include <mutex>
#include <utility>

namespace atmo {

void PassTimings::Add(std::string_view name, double ms) {
  for (PassTiming& entry : entries_) {
    if (entry.name == name) {
      entry.total_ms += ms;
      entry.last_ms = ms;
      ++entry.calls;
      return;
    }
  }
  entries_.push_back(PassTiming{std::string(name), ms, 1, ms});
}

double PassTimings::LastMs(std::string_view name) const {
  for (const PassTiming& entry : entries_) {
    if (entry.name == name) return entry.last_ms;
  }
  return -1.0;
}

namespace {

std::mutex g_progress_mutex;
ProgressHandler g_progress_handler;
double g_progress_min_seconds = 10.0;

}  // namespace

void SetProgressHandler(ProgressHandler handler, double min_seconds) {
  std::lock_guard<std::mutex> lock(g_progress_mutex);
  g_progress_handler = std::move(handler);
  g_progress_min_seconds = min_seconds;
}

namespace progress {

bool Wanted(double estimated_seconds) {
  std::lock_guard<std::mutex> lock(g_progress_mutex);
  return g_progress_handler && estimated_seconds >= g_progress_min_seconds;
}

void Send(const std::string& message) {
  std::lock_guard<std::mutex> lock(g_progress_mutex);
  if (g_progress_handler) g_progress_handler(message);
}

}  // namespace progress

}  // namespace atmo
