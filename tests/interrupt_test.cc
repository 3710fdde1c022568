// SIGINT and SIGTERM during a write: the process ends with the signal, one line on stderr, no
// temporary file left, and the file being replaced keeps its previous content.
#include <signal.h>
#include <spawn.h>
#include <sys/stat.h>
#include <fcntl.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <filesystem>
#include <string>
#include <thread>

#include <gtest/gtest.h>

#include "atmo/error.h"
#include "atmo/hillaire_tables.h"
#include "atmo/interrupt.h"
#include "cli_fixture.h"

extern char** environ;

namespace {

namespace fs = std::filesystem;
using atmo::testing::ReadFile;
using atmo::testing::RunResult;
using atmo::testing::WriteFile;

using InterruptTest = atmo::testing::CliFixture;

// Whether the folder holds one of WriteFileAtomically's temporaries (".NAME.tmp-PID-N").
bool HasTemporary(const fs::path& dir) {
  for (const auto& entry : fs::directory_iterator(dir)) {
    const std::string name = entry.path().filename().string();
    if (name.size() > 1 && name[0] == '.' && name.find(".tmp-") != std::string::npos) return true;
  }
  return false;
}

void InterruptWhileWriting(const fs::path& dir, int signal_number) {
  WriteFile(dir / "big.exr", "previous big.exr");
  // A 4096x2048 equirect: its EXR takes long enough to write (ZIP of 100 MB of floats) that the
  // signal lands while the temporary file exists.
  const std::string command = "cd '" + dir.string() + "' && exec '" ATMO_CLI_PATH
                              "' render --camera equirect --width 4096 --height 2048 --exr big.exr --png big.png "
                              "2>stderr.txt";
  const char* argv[] = {"/bin/sh", "-c", command.c_str(), nullptr};
  pid_t pid = 0;
  ASSERT_EQ(posix_spawn(&pid, "/bin/sh", nullptr, nullptr, const_cast<char* const*>(argv), environ), 0);
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(120);
  bool seen = false;
  while (!seen && std::chrono::steady_clock::now() < deadline) {
    seen = HasTemporary(dir);
    if (!seen) std::this_thread::sleep_for(std::chrono::milliseconds(2));
  }
  ASSERT_TRUE(seen) << "no temporary file appeared";
  ASSERT_EQ(kill(pid, signal_number), 0);
  int status = 0;
  ASSERT_EQ(waitpid(pid, &status, 0), pid);
  ASSERT_TRUE(WIFSIGNALED(status)) << "exit status " << status;
  EXPECT_EQ(WTERMSIG(status), signal_number);
  EXPECT_FALSE(HasTemporary(dir));
  EXPECT_EQ(ReadFile(dir / "big.exr"), "previous big.exr");
  const std::string err = ReadFile(dir / "stderr.txt");
  EXPECT_EQ(err, std::string("atmo: error: interrupted by ") + (signal_number == SIGINT ? "SIGINT" : "SIGTERM") +
                     "; temporary files removed\n");
}

TEST_F(InterruptTest, SigintRemovesTemporariesAndKeepsThePreviousFile) { InterruptWhileWriting(dir_, SIGINT); }
TEST_F(InterruptTest, SigtermRemovesTemporariesAndKeepsThePreviousFile) { InterruptWhileWriting(dir_, SIGTERM); }

// DeferInterrupts, in a child process: a signal raised inside the scope is only recorded (the code
// after it still runs), and at the end of the scope the process ends with it, its temporary file
// removed and its one line on stderr. Only system calls in the child (it is forked from threads).
TEST_F(InterruptTest, ASignalInsideDeferInterruptsWaitsForTheEndOfTheScope) {
  const std::string temporary = (dir_ / ".out.tmp-1").string();
  const std::string marker = (dir_ / "after-the-signal").string();
  const std::string err = (dir_ / "stderr.txt").string();
  const pid_t pid = fork();
  ASSERT_GE(pid, 0);
  if (pid == 0) {
    const int err_fd = ::open(err.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0600);
    ::dup2(err_fd, STDERR_FILENO);
    atmo::InstallInterruptHandlers("atmo");
    ::close(::open(temporary.c_str(), O_WRONLY | O_CREAT, 0600));
    atmo::RegisterTemporaryFile(temporary.c_str());
    {
      const atmo::DeferInterrupts defer;
      ::raise(SIGTERM);
      ::close(::open(marker.c_str(), O_WRONLY | O_CREAT, 0600));  // still runs
    }
    ::_exit(0);  // not reached: the scope's end ends the process
  }
  int status = 0;
  ASSERT_EQ(waitpid(pid, &status, 0), pid);
  ASSERT_TRUE(WIFSIGNALED(status)) << "exit status " << status;
  EXPECT_EQ(WTERMSIG(status), SIGTERM);
  EXPECT_TRUE(fs::exists(marker));
  EXPECT_FALSE(fs::exists(temporary));
  EXPECT_EQ(ReadFile(err), "atmo: error: interrupted by SIGTERM; temporary files removed\n");
}

// The inode of a file (0: none): a rename onto it changes it.
ino_t InodeOf(const fs::path& path) {
  struct stat st {};
  return ::stat(path.c_str(), &st) == 0 ? st.st_ino : 0;
}

// SIGINT and SIGTERM at any moment of a table export leave one whole set that loads: the
// previous one, or the new one when the signal came during the commit (the renames finish first,
// DeferInterrupts). Half the signals are spread over the run, half are sent as soon as the first
// file of the set has been renamed, at the commit. (Whether one lands between two renames, where
// it left new tables beside the old manifest before the deferral, depends on the timing: the test
// above checks the deferral itself.)
TEST_F(InterruptTest, SignalsDuringATableExportLeaveOneWholeSet) {
  const std::string base = "precompute --model hillaire --option transmittance_lut=32x8 --option "
                           "multiple_scattering_lut=8x8 --option sky_view_lut=32x16 --aerial-size 8x8x8 --width 32 "
                           "--height 16 --out sky --sun-elevation ";
  ASSERT_EQ(Run(base + "10").exit_code, 0);
  double published = 10.0;
  int signals = 0, during_commit = 0, finished_first = 0;
  constexpr int kRounds = 24;
  for (int round = 0; round < kRounds; ++round) {
    const double elevation = 11.0 + round;
    const ino_t before = InodeOf(dir_ / "sky_transmittance.raw");
    const std::string command = "cd '" + dir_.string() + "' && exec '" ATMO_CLI_PATH "' " + base +
                                std::to_string(elevation) + " >/dev/null 2>stderr.txt";
    const char* argv[] = {"/bin/sh", "-c", command.c_str(), nullptr};
    pid_t pid = 0;
    ASSERT_EQ(posix_spawn(&pid, "/bin/sh", nullptr, nullptr, const_cast<char* const*>(argv), environ), 0);
    if (round % 2 == 0) {
      std::this_thread::sleep_for(std::chrono::milliseconds(3 * round));
    } else {
      // Until the commit has renamed its first file (or the process is gone).
      const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(60);
      while (InodeOf(dir_ / "sky_transmittance.raw") == before && waitpid(pid, nullptr, WNOHANG) == 0 &&
             std::chrono::steady_clock::now() < deadline) {
      }
    }
    const int signal_number = round % 4 < 2 ? SIGINT : SIGTERM;
    kill(pid, signal_number);  // a zombie not yet waited for still takes it
    ++signals;
    int status = 0;
    waitpid(pid, &status, 0);
    const bool signalled = WIFSIGNALED(status) && WTERMSIG(status) == signal_number;
    const bool finished = WIFEXITED(status) && WEXITSTATUS(status) == 0;
    EXPECT_TRUE(signalled || finished) << "round " << round << ": status " << status << " "
                                       << ReadFile(dir_ / "stderr.txt");
    EXPECT_FALSE(HasTemporary(dir_)) << "round " << round;
    double loaded = -1.0;
    try {
      loaded = atmo::ReadHillaireTables(dir_ / "sky").view.sun_elevation_deg;
    } catch (const atmo::Error& e) {
      ADD_FAILURE() << "round " << round << ": the set does not load: " << e.what();
    }
    EXPECT_TRUE(loaded == published || loaded == elevation) << "round " << round << ": " << loaded;
    if (finished) {
      EXPECT_EQ(loaded, elevation) << "round " << round;
      ++finished_first;
    } else if (loaded == elevation) {
      ++during_commit;  // interrupted inside the commit: the whole new set, then the signal
    }
    published = loaded;
  }
  std::printf("table export: %d signals, %d during the commit (new set kept), %d after the end, %d before\n",
              signals, during_commit, finished_first, signals - during_commit - finished_first);
}

}  // namespace
