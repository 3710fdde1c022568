// Removal of temporary files on SIGINT and SIGTERM (include/atmo/interrupt.h).
//
// The handler may run at any point of any thread, so the registry is a fixed array of slots
// claimed with an atomic flag: Register copies the path into a free slot and only then publishes
// it (release store); the handler reads the published flag (acquire) and unlinks the path.
// unlink, write, signal, raise, pthread_self and pthread_kill are async-signal-safe; nothing here
// allocates or locks.
//
// The handler acts on the thread that installed it (the program's main thread, which stages the
// files): a signal that the kernel delivers to another thread (a oneTBB worker) is passed on to
// it. Otherwise the main thread would run on while the handler unlinks, and could create a
// temporary file after the unlinking and before the process ends (seen under load: a SIGINT
// during `atmo precompute` left one).
#include "atmo/interrupt.h"

#include <pthread.h>
#include <unistd.h>

#include <atomic>
#include <csignal>
#include <cstring>

namespace atmo {
namespace {

enum SlotState : int { kFree = 0, kClaimed = 1, kPublished = 2 };

struct Slot {
  std::atomic<int> state{kFree};
  char path[kMaxTemporaryPathBytes] = {};
};

Slot g_slots[kMaxTemporaryFiles];
const char* g_program = "atmo";
pthread_t g_handling_thread;  // set by InstallInterruptHandlers before the handlers are
std::atomic<bool> g_installed{false};

void WriteAll(const char* text) {
  std::size_t left = std::strlen(text);
  while (left > 0) {
    const ssize_t n = ::write(STDERR_FILENO, text, left);
    if (n <= 0) return;
    text += n;
    left -= static_cast<std::size_t>(n);
  }
}

// DeferInterrupts: while g_deferring > 0 a signal is only recorded in g_pending; the last
// DeferInterrupts to end acts on it. Both sides take g_pending with an exchange, so exactly one
// of them (the handler or the ending scope) finishes the process, whatever their interleaving.
std::atomic<int> g_deferring{0};
std::atomic<int> g_pending{0};
static_assert(std::atomic<int>::is_always_lock_free);

void Finish(int signal_number) {
  for (Slot& slot : g_slots) {
    if (slot.state.load(std::memory_order_acquire) == kPublished) ::unlink(slot.path);
  }
  WriteAll(g_program);
  WriteAll(signal_number == SIGINT ? ": error: interrupted by SIGINT; temporary files removed\n"
                                   : ": error: interrupted by SIGTERM; temporary files removed\n");
  std::signal(signal_number, SIG_DFL);
  std::raise(signal_number);
}

extern "C" void HandleInterrupt(int signal_number) {
  if (g_installed.load() && !pthread_equal(pthread_self(), g_handling_thread)) {
    pthread_kill(g_handling_thread, signal_number);
    return;
  }
  g_pending.store(signal_number);
  if (g_deferring.load() > 0) return;  // the ending DeferInterrupts finishes
  const int pending = g_pending.exchange(0);
  if (pending != 0) Finish(pending);
}

}  // namespace

void InstallInterruptHandlers(const char* program) {
  g_program = program;
  g_handling_thread = pthread_self();
  g_installed.store(true);
  struct sigaction action {};
  action.sa_handler = HandleInterrupt;
  sigemptyset(&action.sa_mask);
  action.sa_flags = 0;
  sigaction(SIGINT, &action, nullptr);
  sigaction(SIGTERM, &action, nullptr);
}

int RegisterTemporaryFile(const char* path) {
  const std::size_t length = std::strlen(path);
  if (length + 1 > kMaxTemporaryPathBytes) return -1;
  for (std::size_t i = 0; i < kMaxTemporaryFiles; ++i) {
    int expected = kFree;
    if (g_slots[i].state.compare_exchange_strong(expected, kClaimed, std::memory_order_acq_rel)) {
      std::memcpy(g_slots[i].path, path, length + 1);
      g_slots[i].state.store(kPublished, std::memory_order_release);
      return static_cast<int>(i);
    }
  }
  return -1;
}

DeferInterrupts::DeferInterrupts() { g_deferring.fetch_add(1); }

DeferInterrupts::~DeferInterrupts() {
  if (g_deferring.fetch_sub(1) != 1) return;
  const int pending = g_pending.exchange(0);
  if (pending != 0) Finish(pending);
}

void ReleaseTemporaryFile(int slot) {
  if (slot < 0 || static_cast<std::size_t>(slot) >= kMaxTemporaryFiles) return;
  g_slots[slot].state.store(kFree, std::memory_order_release);
}

}  // namespace atmo
