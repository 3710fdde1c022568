#include "atmo/timing.h"

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

}  // namespace atmo
