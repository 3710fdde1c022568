#include "atmo/memory.h"

#include <unistd.h>

#include <atomic>
#include <cctype>
#include <cmath>
#include <cstdio>
#include <cstdlib>

#include "atmo/error.h"
#include "printable.h"

namespace atmo {
namespace {

std::atomic<std::uint64_t> g_limit{0};  // 0: the default

constexpr std::uint64_t kDefaultWhenUnknown = std::uint64_t{8} << 30;
constexpr double kMinLimit = 1024.0 * 1024.0;                 // 1 MiB
constexpr double kMaxLimit = 1024.0 * 1024.0 * 1024.0 * 1024.0 * 1024.0;  // 1 PiB

}  // namespace

std::uint64_t PhysicalMemoryBytes() {
  const long pages = sysconf(_SC_PHYS_PAGES);
  const long page = sysconf(_SC_PAGE_SIZE);
  if (pages <= 0 || page <= 0) return 0;
  return static_cast<std::uint64_t>(pages) * static_cast<std::uint64_t>(page);
}

std::uint64_t MemoryLimitBytes() {
  const std::uint64_t set = g_limit.load(std::memory_order_relaxed);
  if (set != 0) return set;
  const std::uint64_t physical = PhysicalMemoryBytes();
  return physical != 0 ? physical / 2 : kDefaultWhenUnknown;
}

void SetMemoryLimitBytes(std::uint64_t bytes) { g_limit.store(bytes, std::memory_order_relaxed); }

std::string FormatBytes(double bytes) {
  const char* units[] = {"bytes", "KB", "MB", "GB", "TB", "PB", "EB"};
  int u = 0;
  while (bytes >= 1024.0 && u < 6) {
    bytes /= 1024.0;
    ++u;
  }
  char text[48];
  if (u == 0) {
    std::snprintf(text, sizeof text, "%.0f bytes", bytes);
  } else {
    std::snprintf(text, sizeof text, "%.1f %s", bytes, units[u]);
  }
  return text;
}

void CheckMemory(std::string_view what, double bytes) {
  const std::uint64_t limit = MemoryLimitBytes();
  if (std::isfinite(bytes) && bytes <= static_cast<double>(limit)) return;
  const bool by_default = g_limit.load(std::memory_order_relaxed) == 0;
  throw Error(std::string(what) + " would need about " + (std::isfinite(bytes) ? FormatBytes(bytes) : "more than 1 EB") +
              ", more than the memory limit of " + FormatBytes(static_cast<double>(limit)) +
              (by_default ? " (half of this machine's memory; --max-memory changes it)" : " (--max-memory)"));
}

std::uint64_t ParseByteSize(std::string_view text) {
  const std::string shown = Printable(text);
  std::string t(text);
  while (!t.empty() && std::isspace(static_cast<unsigned char>(t.back()))) t.pop_back();
  // Strip "B" / "iB", then one of K, M, G, T.
  auto ends_with = [&](std::string_view suffix) {
    if (t.size() < suffix.size()) return false;
    for (std::size_t i = 0; i < suffix.size(); ++i) {
      if (std::tolower(static_cast<unsigned char>(t[t.size() - suffix.size() + i])) != suffix[i]) return false;
    }
    return true;
  };
  if (ends_with("ib")) {
    t.resize(t.size() - 2);
  } else if (ends_with("b")) {
    t.resize(t.size() - 1);
  }
  double scale = 1.0;
  if (!t.empty()) {
    switch (std::tolower(static_cast<unsigned char>(t.back()))) {
      case 'k': scale = 1024.0; break;
      case 'm': scale = 1024.0 * 1024.0; break;
      case 'g': scale = 1024.0 * 1024.0 * 1024.0; break;
      case 't': scale = 1024.0 * 1024.0 * 1024.0 * 1024.0; break;
      default: break;
    }
    if (scale != 1.0) t.pop_back();
  }
  char* end = nullptr;
  const double value = t.empty() ? NAN : std::strtod(t.c_str(), &end);
  if (t.empty() || end != t.c_str() + t.size() || !std::isfinite(value) ||
      std::isspace(static_cast<unsigned char>(t.front()))) {
    throw Error("memory size '" + shown + "': expected a number of bytes with an optional K, M, G or T, e.g. 4G");
  }
  const double bytes = value * scale;
  if (!(bytes >= kMinLimit && bytes <= kMaxLimit)) {
    throw Error("memory size '" + shown + "' is outside [1M, 1024T]");
  }
  return static_cast<std::uint64_t>(bytes);
}

}  // namespace atmo
