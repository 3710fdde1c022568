// Running the `atmo` program from tests: a fixture that gives each test a fresh temporary folder
// and runs the binary there with stdout and stderr captured to files, plus small text helpers.
#pragma once

#include <sys/wait.h>
#include <unistd.h>

#include <cctype>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include <gtest/gtest.h>

namespace atmo::testing {

namespace fs = std::filesystem;

struct RunResult {
  int exit_code = -1;
  std::string out;
  std::string err;
};

inline std::string ReadFile(const fs::path& path) {
  std::ifstream file(path, std::ios::binary);
  std::stringstream buffer;
  buffer << file.rdbuf();
  return buffer.str();
}

inline void WriteFile(const fs::path& path, const std::string& text) {
  std::ofstream file(path, std::ios::binary);
  file << text;
}

inline std::vector<std::string> Lines(const std::string& text) {
  std::vector<std::string> lines;
  std::stringstream stream(text);
  for (std::string line; std::getline(stream, line);) lines.push_back(line);
  return lines;
}

inline std::vector<std::string> Split(const std::string& line, char separator = ',') {
  std::vector<std::string> fields;
  std::stringstream stream(line);
  for (std::string field; std::getline(stream, field, separator);) fields.push_back(field);
  return fields;
}

// Each test gets the folder <tmp>/atmo_<suite>_<test>_<pid>, removed afterwards.
class CliFixture : public ::testing::Test {
 protected:
  void SetUp() override {
    const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
    std::string name = std::string(info->test_suite_name()) + "_" + info->name();
    for (char& c : name) {
      if (!std::isalnum(static_cast<unsigned char>(c))) c = '_';
    }
    dir_ = fs::temp_directory_path() / ("atmo_" + name + "_" + std::to_string(::getpid()));
    fs::remove_all(dir_);
    fs::create_directories(dir_);
  }
  void TearDown() override {
    std::error_code ignored;
    fs::remove_all(dir_, ignored);
  }

  // Runs `atmo <args>` (a shell-quoted string) in the test's folder; with timeout_s > 0 through
  // `timeout`, so that a hang ends as exit code 124 rather than blocking the test.
  RunResult Run(const std::string& args, int timeout_s = 0) const {
    const std::string limit = timeout_s > 0 ? "timeout " + std::to_string(timeout_s) + " " : "";
    const std::string command =
        "cd '" + dir_.string() + "' && " + limit + "'" ATMO_CLI_PATH "' " + args + " >stdout.txt 2>stderr.txt";
    const int status = std::system(command.c_str());
    RunResult result;
    result.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
    result.out = ReadFile(dir_ / "stdout.txt");
    result.err = ReadFile(dir_ / "stderr.txt");
    return result;
  }

  // Runs `args`, which must fail: a non-zero exit, one `atmo: error:` line on stderr naming
  // `message_part`, and each of `outputs` (written here with "previous NAME" first) untouched.
  RunResult ExpectFailureKeepingOutputs(const std::string& args, const std::string& message_part,
                                        const std::vector<std::string>& outputs) const {
    for (const std::string& output : outputs) WriteFile(dir_ / output, "previous " + output);
    const RunResult r = Run(args);
    EXPECT_NE(r.exit_code, 0);
    EXPECT_EQ(r.err.rfind("atmo: error:", 0), 0u) << r.err;
    EXPECT_EQ(Lines(r.err).size(), 1u) << r.err;
    EXPECT_NE(r.err.find(message_part), std::string::npos) << r.err;
    for (const std::string& output : outputs) {
      EXPECT_EQ(ReadFile(dir_ / output), "previous " + output) << output;
    }
    return r;
  }

  fs::path dir_;
};

}  // namespace atmo::testing
