// The manual against the program: every command of the README's examples runs and succeeds, and
// every example output in docs/cli.md is what the current build prints.
//
// 1. README.md: each line of a ```sh block is a command (a trailing `\` joins the next line, a
//    ` #` starts a comment). They run in order in one fresh folder (so that `printf ... > grid.csv`
//    and `atmo presets --dump earth > hazy.json` feed the commands after them), `atmo` being the
//    binary under test, and each must exit 0. The only commands left out are those of kSkipped,
//    each with its reason; an entry that matches no README command fails the test, so the list
//    cannot outlive the README. Commands with `--backend gl` run only where a GL context can be made.
// 2. README.md and every page under docs/: a ```sh block whose lines start with `$ ` is a
//    transcript (docs/cli.md has most of them). `$ cat FILE` followed
//    by lines writes them to FILE (the transcript shows the input it uses); `$ atmo ...` is run and
//    its standard output then standard error must equal the lines that follow, line by line: the
//    text exactly, each number within a relative 1e-6 (last-digit differences of FMA builds), and
//    a number followed by ` s` or ` ms` (a timing) matching any number. scripts/doc_transcripts.py
//    reruns them and rewrites the outputs (`--check` reports the drift without writing).
// 3. Every `atmo:KEY` EXR attribute that render_command.cc and sun_options.cc write is named in
//    docs/cli.md.
#include <sys/wait.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <regex>
#include <sstream>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "cli_fixture.h"

namespace {

namespace fs = std::filesystem;
using atmo::testing::Lines;
using atmo::testing::ReadFile;
using atmo::testing::WriteFile;

// README commands that this test does not run, and why. Matched as a prefix of the command.
struct Skipped {
  const char* prefix;
  const char* reason;
};
constexpr Skipped kSkipped[] = {
    {"./scripts/install_deps.sh", "installs packages and builds the project (what ran this test)"},
    {"ctest", "runs this test suite"},
    {"./build/tests/atmo_tests", "runs this test suite"},
    {"./build/bench/atmo_bench", "the Google Benchmark programs: about a minute"},
    {"atmo compare --model hillaire --against reference", "a 16384-path reference on 4725 configurations: minutes"},
    {"atmo compare --model elek", "the default 4096-path reference on 4725 configurations: minutes"},
    {"atmo render --model reference", "44 million paths: about a minute on two cores"},
    {"atmo render --model hillaire --option sky_view=off", "a per-pixel ray march of a 1280x720 frame: 5-20 s on two cores"},
    {"atmo render --date 2026-06-21T04:00+02:00 --until", "a 109-frame time-lapse: about a minute"},
    {"atmo annual --epw site.epw", "a year of the reader's weather file, about 15 min (tests/annual_test.cc and "
                                   "tests/cli_daylight_test.cc run atmo annual on days of the repository's TMY3 file)"},
    {"cmake --install build", "installs this build outside the test folder (the package_install test "
                              "installs into build/package_test/prefix)"},
    {"cmake -S myproject", "a project of the reader's (package_cmake_consumer_build builds tests/consumer)"},
    {"c++ -std=c++20 main.cc", "the reader's program (package_pkg_config builds tests/consumer/main.cc so)"},
    {"atmo-viewer", "opens a window until it is closed (tests/viewer/viewer_test.cc runs the viewer under Xvfb)"},
    {"./build/apps/viewer/atmo-viewer", "the set-up's viewer command: opens a window until it is closed"},
    {"xvfb-run -a atmo-viewer --hidden --frames 31", "31 frames at 1280x720 under llvmpipe, about 10 s "
                                                      "(tests/viewer/viewer_test.cc runs scripts on small frames)"},
    {"xvfb-run -a atmo-viewer --hidden --frames 40", "the viewer's benchmark, 40 frames with every table: about 10 s"},
    {"atmo render --backend gl --model elek", "the elek table on the GL backend: 10 s under Mesa llvmpipe "
                                              "(gl_elek_test.cc runs it on a small table)"},
};

std::string Trim(std::string text) {
  while (!text.empty() && (text.back() == ' ' || text.back() == '\r')) text.pop_back();
  std::size_t start = 0;
  while (start < text.size() && text[start] == ' ') ++start;
  return text.substr(start);
}

// The command of a README line: the text before a ` #` that is outside quotes.
std::string WithoutComment(const std::string& line) {
  char quote = 0;
  for (std::size_t i = 0; i < line.size(); ++i) {
    const char c = line[i];
    if (quote != 0) {
      if (c == quote) quote = 0;
    } else if (c == '\'' || c == '"') {
      quote = c;
    } else if (c == '#' && (i == 0 || line[i - 1] == ' ')) {
      return Trim(line.substr(0, i));
    }
  }
  return Trim(line);
}

// The ```sh blocks of a Markdown file, each as its lines.
std::vector<std::vector<std::string>> ShellBlocks(const std::string& markdown) {
  std::vector<std::vector<std::string>> blocks;
  bool inside = false;
  for (const std::string& raw : Lines(markdown)) {
    const std::string line = Trim(raw);
    if (!inside && line == "```sh") {
      inside = true;
      blocks.emplace_back();
    } else if (inside && line == "```") {
      inside = false;
    } else if (inside) {
      blocks.back().push_back(raw);
    }
  }
  return blocks;
}

struct Output {
  int exit_code = -1;
  std::string text;  // stdout, then stderr
  double seconds = 0.0;
};

// Runs a shell command line in `dir`, `atmo` at its start being the binary under test.
// Runs COMMAND in DIR ("atmo" is the built CLI), killed after TIMEOUT_S seconds.
Output RunShell(const fs::path& dir, std::string command, int timeout_s = 120) {
  if (command.rfind("atmo ", 0) == 0 || command == "atmo") command = "'" ATMO_CLI_PATH "'" + command.substr(4);
  const std::string line = "cd '" + dir.string() + "' && (timeout " + std::to_string(timeout_s) + " " + command +
                           ") >stdout.txt 2>stderr.txt";
  const auto start = std::chrono::steady_clock::now();
  const int status = std::system(line.c_str());
  Output output;
  output.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  output.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  output.text = ReadFile(dir / "stdout.txt") + ReadFile(dir / "stderr.txt");
  return output;
}

bool HaveGlContext(const fs::path& dir) {
#ifdef ATMO_HAVE_GL
  return RunShell(dir, "atmo render --model hillaire --preset earth --backend gl --width 4 --height 4 --no-exr --no-png").exit_code == 0;
#else
  (void)dir;
  return false;
#endif
}

// COMMAND with one repeat when it is an `atmo bench` (its --quick or --repeat N replaced).
std::string OneRepeat(std::string command) {
  if (command.rfind("atmo bench", 0) != 0) return command;
  std::istringstream words(command);
  std::string out;
  for (std::string word; words >> word;) {
    if (word == "--quick") continue;
    if (word == "--repeat") {
      words >> word;  // its count
      continue;
    }
    out += (out.empty() ? "" : " ") + word;
  }
  return out + " --repeat 1";
}

class DocsTest : public atmo::testing::CliFixture {};

TEST_F(DocsTest, EveryReadmeExampleRuns) {
  const std::string readme = ReadFile(fs::path(ATMO_SOURCE_DIR) / "README.md");
  ASSERT_FALSE(readme.empty());
  const bool gl = HaveGlContext(dir_);
  // The commands share a table cache in the test's folder, as a reader's do in ~/.cache: the
  // examples that use one atmosphere (earth-spectral four times) compute its tables once.
  const char* kept = std::getenv("ATMO_TABLE_CACHE");
  const std::string previous = kept != nullptr ? kept : "";
  ::setenv("ATMO_TABLE_CACHE", (dir_ / "table-cache").c_str(), 1);
  struct Restore {
    bool had;
    std::string value;
    ~Restore() { had ? ::setenv("ATMO_TABLE_CACHE", value.c_str(), 1) : ::unsetenv("ATMO_TABLE_CACHE"); }
  } restore{kept != nullptr, previous};
  std::vector<int> skip_used(std::size(kSkipped), 0);
  int ran = 0;
  double total_s = 0.0;
  for (const std::vector<std::string>& block : ShellBlocks(readme)) {
    std::string pending;
    for (const std::string& raw : block) {
      std::string line = WithoutComment(raw);
      if (!line.empty() && line.back() == '\\') {
        line.pop_back();
        pending += line + " ";
        continue;
      }
      const std::string command = Trim(pending + line);
      pending.clear();
      if (command.empty()) continue;
      const Skipped* skipped = nullptr;
      for (std::size_t i = 0; i < std::size(kSkipped); ++i) {
        if (command.rfind(kSkipped[i].prefix, 0) == 0) {
          skipped = &kSkipped[i];
          ++skip_used[i];
        }
      }
      if (skipped != nullptr) {
        std::printf("skipped (%s): %s\n", skipped->reason, command.c_str());
        continue;
      }
      if (!gl && command.find("--backend gl") != std::string::npos) {
        std::printf("skipped (no GL context here): %s\n", command.c_str());
        continue;
      }
      const Output output = RunShell(dir_, command);
      total_s += output.seconds;
      ++ran;
      std::printf("%5.2f s  %s\n", output.seconds, command.c_str());
      EXPECT_EQ(output.exit_code, 0) << command << "\n" << output.text;
    }
  }
  std::printf("%d README commands in %.1f s\n", ran, total_s);
  EXPECT_GE(ran, 20);
  for (std::size_t i = 0; i < std::size(kSkipped); ++i) {
    EXPECT_GT(skip_used[i], 0) << "kSkipped entry '" << kSkipped[i].prefix << "' matches no README command";
  }
}

// A line of text cut into numbers and the text between them.
struct Token {
  bool is_number = false;
  double value = 0.0;
  std::string text;
};

std::vector<Token> Tokenize(const std::string& line) {
  std::vector<Token> tokens;
  std::size_t i = 0;
  while (i < line.size()) {
    const char c = line[i];
    const bool starts_number = std::isdigit(static_cast<unsigned char>(c)) ||
                               ((c == '-' || c == '.') && i + 1 < line.size() &&
                                std::isdigit(static_cast<unsigned char>(line[i + 1])) &&
                                (i == 0 || !std::isalnum(static_cast<unsigned char>(line[i - 1]))));
    if (starts_number) {
      char* end = nullptr;
      const double value = std::strtod(line.c_str() + i, &end);
      const std::size_t length = static_cast<std::size_t>(end - (line.c_str() + i));
      if (length > 0) {
        tokens.push_back({true, value, line.substr(i, length)});
        i += length;
        continue;
      }
    }
    if (tokens.empty() || tokens.back().is_number) tokens.push_back({false, 0.0, ""});
    tokens.back().text += c;
    ++i;
  }
  return tokens;
}

// Whether `actual` is `expected` up to number tolerance and masked timings; `why` says where not.
bool LineMatches(const std::string& expected, const std::string& actual, std::string& why) {
  const std::vector<Token> e = Tokenize(expected);
  const std::vector<Token> a = Tokenize(actual);
  if (e.size() != a.size()) {
    why = "a different layout";
    return false;
  }
  for (std::size_t i = 0; i < e.size(); ++i) {
    if (e[i].is_number != a[i].is_number) {
      why = "'" + e[i].text + "' against '" + a[i].text + "'";
      return false;
    }
    if (!e[i].is_number) {
      if (e[i].text != a[i].text) {
        why = "'" + e[i].text + "' against '" + a[i].text + "'";
        return false;
      }
      continue;
    }
    const bool timing = i + 1 < e.size() && (e[i + 1].text.rfind(" s", 0) == 0 || e[i + 1].text.rfind(" ms", 0) == 0);
    if (timing) continue;
    const double tolerance = 1e-6 * std::max(std::fabs(e[i].value), std::fabs(a[i].value)) + 1e-300;
    if (!(std::fabs(e[i].value - a[i].value) <= tolerance)) {
      why = "the number " + e[i].text + " is " + a[i].text;
      return false;
    }
  }
  return true;
}

// The Markdown files whose transcripts are checked: the README and every page under docs/.
std::vector<fs::path> ManualPages() {
  const fs::path source = fs::path(ATMO_SOURCE_DIR);
  std::vector<fs::path> pages = {source / "README.md"};
  for (const auto& entry : fs::recursive_directory_iterator(source / "docs")) {
    if (entry.is_regular_file() && entry.path().extension() == ".md") pages.push_back(entry.path());
  }
  std::sort(pages.begin(), pages.end());
  return pages;
}

TEST_F(DocsTest, CliExampleOutputsAreTheCurrentOnes) {
  int transcripts = 0;
  int cli_transcripts = 0;
  for (const fs::path& page : ManualPages()) {
    const std::string manual = ReadFile(page);
    ASSERT_FALSE(manual.empty()) << page;
    const bool is_cli = page.filename() == "cli.md";
    for (const std::vector<std::string>& block : ShellBlocks(manual)) {
      if (block.empty() || block.front().rfind("$ ", 0) != 0) continue;  // not a transcript
      // Each `$ ` line and the lines after it up to the next one.
      for (std::size_t i = 0; i < block.size();) {
        const std::string command = block[i].substr(2);
        std::vector<std::string> expected;
        for (++i; i < block.size() && block[i].rfind("$ ", 0) != 0; ++i) expected.push_back(block[i]);
        if (command.rfind("cat ", 0) == 0) {
          std::string text;
          for (const std::string& line : expected) text += line + "\n";
          WriteFile(dir_ / command.substr(4), text);
          continue;
        }
        ++transcripts;
        if (is_cli) ++cli_transcripts;
        const Output output = RunShell(dir_, command);
        const std::vector<std::string> actual = Lines(output.text);
        std::string got;
        for (const std::string& line : actual) got += line + "\n";
        ASSERT_EQ(actual.size(), expected.size()) << "$ " << command << " printed:\n" << got;
        for (std::size_t k = 0; k < expected.size(); ++k) {
          std::string why;
          EXPECT_TRUE(LineMatches(expected[k], actual[k], why))
              << page.filename().string() << ": $ " << command << ", line " << k + 1 << ": " << why
              << "\n  docs: " << expected[k]
              << "\n  now:  " << actual[k] << "\n  (scripts/doc_transcripts.py rewrites the outputs)";
        }
      }
    }
  }
  EXPECT_GE(cli_transcripts, 3) << "docs/cli.md has lost its example transcripts";
  EXPECT_GE(transcripts, cli_transcripts + 1) << "docs/reliability.md has lost its memory-limit transcript";
}

// A measured block of the manual (`<!-- measured: COMMAND -->`, a ```text block of the command's
// output, a "Measured ... on MACHINE, ... load L." stamp, `<!-- end measured -->`): its numbers are
// measurements that scripts/doc_transcripts.py regenerates with the stamp, so only the layout is
// checked here: the command still runs and prints the same lines with every number masked.
TEST_F(DocsTest, MeasuredOutputsKeepTheirLayoutAndStamp) {
  int blocks = 0;
  for (const fs::path& page : ManualPages()) {
    const std::vector<std::string> lines = Lines(ReadFile(page));
    for (std::size_t i = 0; i < lines.size(); ++i) {
      const std::string line = Trim(lines[i]);
      const std::string open = "<!-- measured: ";
      if (line.rfind(open, 0) != 0) continue;
      const std::string command = line.substr(open.size(), line.size() - open.size() - 4);
      std::vector<std::string> expected;
      std::string stamp;
      std::size_t k = i + 1;
      bool inside = false;
      for (; k < lines.size() && Trim(lines[k]) != "<!-- end measured -->"; ++k) {
        if (Trim(lines[k]) == "```text") {
          inside = true;
        } else if (inside && Trim(lines[k]) == "```") {
          inside = false;
        } else if (inside) {
          expected.push_back(lines[k]);
        } else if (lines[k].rfind("Measured ", 0) == 0) {
          stamp = lines[k];
        }
      }
      ASSERT_LT(k, lines.size()) << page << ": '" << line << "' has no end";
      ++blocks;
      if (command.find("--backend gl") != std::string::npos && !HaveGlContext(dir_)) continue;
      EXPECT_NE(stamp.find(" cores, load "), std::string::npos) << page << ": `" << command << "` has no stamp";
      // The layout does not depend on the number of repeats: `atmo bench` runs once here (its
      // measured runs take up to a minute, several on a loaded CI machine).
      const Output output = RunShell(dir_, OneRepeat(command), 600);
      ASSERT_EQ(output.exit_code, 0) << page << ": `" << OneRepeat(command) << "` printed:\n" << output.text;
      const std::vector<std::string> actual = Lines(output.text);
      ASSERT_EQ(actual.size(), expected.size()) << page << ": `" << command << "` printed:\n" << output.text;
      for (std::size_t n = 0; n < expected.size(); ++n) {
        const std::vector<Token> e = Tokenize(expected[n]);
        const std::vector<Token> a = Tokenize(actual[n]);
        // Columns padded to the numbers' widths: runs of spaces count as one.
        const auto collapsed = [](const std::string& text) {
          std::string out;
          for (char c : text) {
            if (c != ' ' || out.empty() || out.back() != ' ') out += c;
          }
          return out;
        };
        bool same = e.size() == a.size();
        for (std::size_t t = 0; same && t < e.size(); ++t) {
          same = e[t].is_number == a[t].is_number && (e[t].is_number || collapsed(e[t].text) == collapsed(a[t].text));
        }
        EXPECT_TRUE(same) << page.filename().string() << ": `" << command << "`, line " << n + 1
                          << "\n  docs: " << expected[n] << "\n  now:  " << actual[n]
                          << "\n  (scripts/doc_transcripts.py reruns it)";
      }
    }
  }
  EXPECT_GE(blocks, 1) << "docs/performance.md has lost its measured atmo bench";
}

// Every timing of the manual (a number followed by ms, µs, s, min or fps) is regenerated by a script
// or is a dated record: inside a measured block, a generated table (`<!-- table: NAME -->`), a
// transcript or a record (`<!-- record: YYYY-MM-DD -->` ... `<!-- end record -->`, the date also in
// its visible text). Bounds (after ≤, ≥, <, >) and lines that end with `<!-- not measured: WHY -->`
// (a setting, a default) are not measurements. `scripts/doc_transcripts.py --timings` lists the
// lines this test would name.
TEST(DocsTimings, EveryTimingIsRegeneratedOrARecord) {
  const std::regex timing(R"(\d\s?(?:ms|µs|s|min|fps)\b)");
  const std::regex bound(R"((?:≤|≥|<|>)\s?~?\d+(?:[.,]\d+)?\s?(?:ms|µs|s|min|fps)\b)");
  const std::regex record(R"(^<!-- record: (\d{4}-\d{2}-\d{2})\b.* -->$)");
  int records = 0;
  for (const fs::path& page : ManualPages()) {
    const std::vector<std::string> lines = Lines(ReadFile(page));
    std::string closing;     // the end of the block the line is in ("" outside blocks)
    std::string date;        // a record's date, until its visible text shows it
    bool sh = false;
    for (std::size_t i = 0; i < lines.size(); ++i) {
      const std::string line = Trim(lines[i]);
      const std::string where = page.filename().string() + ":" + std::to_string(i + 1) + ": ";
      if (!closing.empty()) {
        if (!date.empty() && line.find(date) != std::string::npos) date.clear();
        if (line == closing) {
          EXPECT_TRUE(date.empty()) << where << "a record's text does not show its date " << date;
          closing.clear();
          date.clear();
        }
        continue;
      }
      for (const char* kind : {"measured", "table", "record"}) {
        if (line.rfind(std::string("<!-- ") + kind + ": ", 0) == 0) closing = std::string("<!-- end ") + kind + " -->";
      }
      if (line.rfind("<!-- record: ", 0) == 0) {
        std::smatch match;
        EXPECT_TRUE(std::regex_match(line, match, record)) << where << "a record needs its date: " << line;
        if (!match.empty()) date = match[1].str();
        ++records;
      }
      if (!closing.empty()) continue;
      if (line.rfind("```sh", 0) == 0) {
        sh = true;
        continue;
      }
      if (sh) {
        sh = line != "```";
        continue;
      }
      if (line.find("<!-- not measured: ") != std::string::npos) continue;
      EXPECT_FALSE(std::regex_search(std::regex_replace(lines[i], bound, ""), timing))
          << where << lines[i] << "\n  (a timing nothing regenerates: a measured block, or a dated record)";
    }
    EXPECT_TRUE(closing.empty()) << page << ": a block has no " << closing;
  }
  EXPECT_GE(records, 1);
}

// Every EXR attribute the render command writes ("atmo:KEY" in its sources) is in cli.md's table.
TEST(DocsExrAttributes, EveryWrittenAttributeIsDocumented) {
  const fs::path source = fs::path(ATMO_SOURCE_DIR);
  const std::string manual = ReadFile(source / "docs" / "cli.md");
  int found = 0;
  for (const char* file : {"render_command.cc", "sun_options.cc"}) {
    const std::string code = ReadFile(source / "apps" / "atmo" / file);
    for (std::size_t at = code.find("\"atmo:"); at != std::string::npos; at = code.find("\"atmo:", at + 1)) {
      const std::size_t end = code.find('"', at + 1);
      const std::string key = code.substr(at + 1, end - at - 1);
      ++found;
      EXPECT_NE(manual.find("`" + key + "`"), std::string::npos) << key << " (" << file << ") is not in docs/cli.md";
    }
  }
  EXPECT_GE(found, 20);
}

TEST(DocsTokens, BenchLayoutRunsOnce) {
  EXPECT_EQ(OneRepeat("atmo bench --backend gl --quick"), "atmo bench --backend gl --repeat 1");
  EXPECT_EQ(OneRepeat("atmo bench --model elek --repeat 3 --preset x"), "atmo bench --model elek --preset x --repeat 1");
  EXPECT_EQ(OneRepeat("atmo render --quick"), "atmo render --quick");
}

TEST(DocsTokens, NumbersTimingsAndText) {
  std::string why;
  EXPECT_TRUE(LineMatches("a 7.762013469e-03,0.5", "a 7.7620134690e-03,0.5", why));
  EXPECT_FALSE(LineMatches("a 7.762013469e-03", "a 7.762113469e-03", why));
  EXPECT_TRUE(LineMatches("in 0.41 s: frame 61.3 ms", "in 12 s: frame 0.2 ms", why));
  EXPECT_FALSE(LineMatches("wrote sky.exr", "wrote sky.png", why));
  EXPECT_FALSE(LineMatches("1280x720", "1280x72", why));
}

}  // namespace
