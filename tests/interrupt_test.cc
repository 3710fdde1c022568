// SIGINT and SIGTERM during a write: the process ends with the signal, one line on stderr, no
// temporary file left, and the file being replaced keeps its previous content.
#include <signal.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <filesystem>
#include <string>
#include <thread>

#include <gtest/gtest.h>

#include "cli_fixture.h"

extern char** environ;

namespace {

namespace fs = std::filesystem;
using atmo::testing::ReadFile;
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

}  // namespace
