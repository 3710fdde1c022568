// Interrupted runs leave nothing behind: SIGINT and SIGTERM remove the temporary files that
// atmo's writers (WriteFileAtomically, include/atmo/image.h) have open, print one line and end
// the process with the signal's status. A file that was being replaced keeps its previous
// content: the rename onto it happens only after a complete write.
//
// To use it (a program that writes with atmo; the atmo CLI does it first thing):
//   atmo::InstallInterruptHandlers("atmo");
#pragma once

#include <cstddef>

namespace atmo {

// Installs handlers for SIGINT and SIGTERM. On a signal the handler unlinks every registered
// temporary file, writes "<program>: error: interrupted by SIGINT; temporary files removed" to
// stderr, restores the default action and raises the signal again (exit status 128 + signal).
// Everything it does is async-signal-safe. `program` must outlive the process (a literal).
// The handler runs on the calling thread (the one that stages the files): a signal delivered to
// another thread is passed on to it, so no file can be staged after the handler's unlinking.
void InstallInterruptHandlers(const char* program);

// The registry the handlers empty. A slot holds one path until Release; Register returns -1
// (the file is then simply not removed on a signal) when all kMaxTemporaryFiles slots are taken
// or the path is longer than kMaxTemporaryPathBytes - 1.
inline constexpr std::size_t kMaxTemporaryFiles = 64;
inline constexpr std::size_t kMaxTemporaryPathBytes = 4096;
int RegisterTemporaryFile(const char* path);
void ReleaseTemporaryFile(int slot);

// While one lives (in any thread), SIGINT and SIGTERM wait: the handler records the signal, and
// the last DeferInterrupts to end acts on it (removes the temporaries, prints the line, ends the
// process with the signal). AtomicFileSet::Commit holds one over its renames, so that a signal
// never leaves a set half published (the new tables beside the old manifest).
class DeferInterrupts {
 public:
  DeferInterrupts();
  ~DeferInterrupts();
  DeferInterrupts(const DeferInterrupts&) = delete;
  DeferInterrupts& operator=(const DeferInterrupts&) = delete;
};

}  // namespace atmo
