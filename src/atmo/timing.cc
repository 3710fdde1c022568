#include "atmo/timing.h"

#include <mutex>
#include <utility>

namespace atmo {

PassTiming& PassTimings::Entry(std::string_view name) const {
  for (PassTiming& entry : entries_) {
    if (entry.name == name) return entry;
  }
  entries_.push_back(PassTiming{std::string(name), 0.0, 0, 0.0});
  return entries_.back();
}

void PassTimings::Record(PassTiming& entry, double ms) {
  entry.total_ms += ms;
  entry.last_ms = ms;
  ++entry.calls;
}

void PassTimings::Add(std::string_view name, double ms) { Record(Entry(name), ms); }

void PassTimings::AddDeferred(std::string_view name, DeferredMs read) {
  Entry(name);  // its place in the order of first use
  pending_.push_back(Pending{std::string(name), std::move(read)});
}

bool PassTimings::Collect(bool wait) const {
  while (!pending_.empty()) {
    Pending& next = pending_.front();
    const std::optional<double> ms = next.read(wait);
    if (!ms) {
      if (!wait) return false;
      // Unreadable even when waited for (its GL context is not current here): dropped.
    } else {
      Record(Entry(next.name), *ms);
    }
    pending_.pop_front();
  }
  return true;
}

double PassTimings::LastMs(std::string_view name) const {
  Collect(true);
  for (const PassTiming& entry : entries_) {
    if (entry.name == name) return entry.calls > 0 ? entry.last_ms : -1.0;
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
