// A progress bar on stderr for long runs: `\r[#########           ] 42% 1.2 s, ETA 1.7 s`.
// It draws only when stderr is a terminal (isatty(2)), so logs and tests stay clean, and only
// once a run has taken more than a second; Finish() ends the line it drew.
#pragma once

#include <unistd.h>

#include <chrono>
#include <cstdio>
#include <string>
#include <utility>

namespace atmo::cli {

class ProgressBar {
 public:
  explicit ProgressBar(std::string label) : label_(std::move(label)), enabled_(isatty(2) != 0) {}
  ~ProgressBar() { Finish(); }

  // Reports that `done` of `total` units are complete.
  void Update(double done, double total) {
    const double elapsed = std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count();
    if (!enabled_ || elapsed < 1.0 || total <= 0.0) return;
    const double fraction = done / total;
    char bar[31] = {};
    for (int i = 0; i < 30; ++i) bar[i] = i < static_cast<int>(fraction * 30.0) ? '#' : ' ';
    const double eta = fraction > 0.0 ? elapsed * (1.0 - fraction) / fraction : 0.0;
    std::fprintf(stderr, "\r%s [%s] %3.0f%% %.1f s, ETA %.1f s ", label_.c_str(), bar, 100.0 * fraction, elapsed, eta);
    std::fflush(stderr);
    drawn_ = true;
  }
  void Finish() {
    if (drawn_) std::fputc('\n', stderr);
    drawn_ = false;
  }

 private:
  std::string label_;
  bool enabled_;
  bool drawn_ = false;
  std::chrono::steady_clock::time_point start_ = std::chrono::steady_clock::now();
};

}  // namespace atmo::cli
