// Fuzz targets of atmo's input parsers (docs/reliability.md, "Fuzzing").
//
// Each target is a plain function over the bytes of one input, linked both by its libFuzzer
// binary (fuzz/libfuzzer_main.cc, built with -DATMO_FUZZ=ON under clang) and by the replay test
// (tests/fuzz_replay_test.cc, every build), which runs every file of fuzz/corpus/<target>/ and
// fuzz/regressions/<target>/ through it.
//
// The contract each target checks: the parser either accepts the input or throws atmo::Error
// with a one-line message. Any other exception escapes (libFuzzer reports it as a crash, the
// replay test as a failure), and so does a broken invariant of an accepted input
// (FuzzInvariantError). The return value is always 0 (libFuzzer's convention).
//
// To add a target: write its function here and in fuzz_targets.cc, add it to kFuzzTargets and to
// ATMO_FUZZ_TARGETS in fuzz/CMakeLists.txt, and give it fuzz/corpus/<name>/ (seeds),
// fuzz/<name>.dict (optional) and fuzz/regressions/<name>/ (crashes found, kept).
#pragma once

#include <cstddef>
#include <cstdint>
#include <span>
#include <stdexcept>
#include <string_view>

namespace atmo::fuzz {

// A broken invariant of an input that the parser accepted (not an atmo::Error: it must escape).
class FuzzInvariantError : public std::logic_error {
 public:
  using std::logic_error::logic_error;
};

// atmo::FromJson (the parameters of --config): accepted parameters validate and survive
// ToJson -> FromJson unchanged (but for the name, a label).
int FuzzJsonParameters(const std::uint8_t* data, std::size_t size);

// atmo::LoadElekTable (--table NAME) of a small elek model (preset atmosphere-plus, size 4x8x4,
// orders 1): the input is NAME.json, then the line kElekRawSeparator, then the bytes of NAME.raw
// (no separator: an empty NAME.raw). Written to a private temporary folder and loaded; a loaded
// table has the model's size.
int FuzzElekTable(const std::uint8_t* data, std::size_t size);
inline constexpr std::string_view kElekRawSeparator = "\n--atmo-fuzz-raw--\n";

// atmo::cli::ParseGrid (the IN.csv of sample --grid and compare --grid): every accepted point
// passes CheckPoint (finite, zenith angles in [0, 180], altitude within the bounds).
int FuzzGridCsv(const std::uint8_t* data, std::size_t size);

// atmo::ReadExr (the images of compare --image, tables, cube maps): the bytes as an .exr file in a
// private temporary folder; an accepted image has the layout Image promises.
int FuzzExrReader(const std::uint8_t* data, std::size_t size);

// atmo::ReadHillaireTables (the export of `atmo precompute --model hillaire --out sky`): the input
// is sky.json, then for each table of kHillaireTableNames in order the line kRawSeparator and the
// bytes of sky_<table>.raw (a table without its separator: an empty file). Written to a private
// temporary folder and read; an accepted set has its six tables in order, each of the size its
// sides and batches give, the batches of its parameters, the two sky views of one size and the
// two aerial tables of one size, which is the view's aerial-perspective volume; its parameters and
// view are valid.
int FuzzHillaireTable(const std::uint8_t* data, std::size_t size);
inline constexpr std::string_view kRawSeparator = kElekRawSeparator;

struct FuzzTarget {
  std::string_view name;  // the folder names under fuzz/corpus and fuzz/regressions
  int (*run)(const std::uint8_t* data, std::size_t size);
};

// Every target, by name.
inline constexpr FuzzTarget kFuzzTargets[] = {
    {"json_parameters", &FuzzJsonParameters},
    {"elek_table", &FuzzElekTable},
    {"grid_csv", &FuzzGridCsv},
    {"exr_reader", &FuzzExrReader},
    {"hillaire_table", &FuzzHillaireTable},
};

}  // namespace atmo::fuzz
