// The fuzz targets (fuzz_targets.h).
#include "fuzz_targets.h"

#include <stdlib.h>
#include <unistd.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <memory>
#include <string>
#include <vector>

#include "atmo/aerial_perspective.h"
#include "atmo/error.h"
#include "atmo/hillaire_tables.h"
#include "atmo/image.h"
#include "atmo/model.h"
#include "atmo/parameters.h"
#include "grid.h"
#include "io/elek_table_file.h"
#include "io/hillaire_table_file.h"
#include "models/elek_model.h"
#include "physics/shared_parameters.h"

namespace atmo::fuzz {
namespace {

namespace fs = std::filesystem;

std::string_view Text(const std::uint8_t* data, std::size_t size) {
  return {reinterpret_cast<const char*>(data), size};
}

void Require(bool condition, const std::string& what) {
  if (!condition) throw FuzzInvariantError(what);
}

// Runs `parse`; an atmo::Error is a refusal, which must be one non-empty line.
template <typename Parse>
int Refusable(Parse parse) {
  try {
    parse();
  } catch (const Error& e) {
    const std::string_view message = e.what();
    Require(!message.empty(), "an empty error message");
    Require(message.find('\n') == std::string_view::npos, "an error message of more than one line: " + std::string(message));
  }
  return 0;
}

// A private folder for the files of one process (the targets that read files), removed at exit.
const fs::path& ScratchFolder() {
  static const fs::path folder = [] {
    const char* base = std::getenv("TMPDIR");
    std::string pattern = std::string(base != nullptr && *base != '\0' ? base : "/tmp") + "/atmo-fuzz-XXXXXX";
    if (::mkdtemp(pattern.data()) == nullptr) throw FuzzInvariantError("cannot make a temporary folder " + pattern);
    std::atexit([] {
      std::error_code ec;
      fs::remove_all(ScratchFolder(), ec);
    });
    return fs::path(pattern);
  }();
  return folder;
}

void WriteBytes(const fs::path& path, std::string_view bytes) {
  std::ofstream out(path, std::ios::binary | std::ios::trunc);
  out.write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
  out.close();
  if (!out) throw FuzzInvariantError("cannot write " + path.string());
}

}  // namespace

int FuzzJsonParameters(const std::uint8_t* data, std::size_t size) {
  return Refusable([&] {
    const AtmosphereParameters p = FromJson(Text(data, size));
    // Accepted parameters are valid, and their JSON reads back as the same parameters.
    try {
      Validate(p);
      // The name is a label ("custom" or the preset the values equal), recomputed on reading.
      AtmosphereParameters back = FromJson(ToJson(p));
      back.name = p.name;
      Require(back == p, "ToJson -> FromJson changed the parameters: " + ToJson(p));
    } catch (const Error& e) {
      throw FuzzInvariantError(std::string("accepted parameters fail on their own JSON: ") + e.what());
    }
  });
}

int FuzzElekTable(const std::uint8_t* data, std::size_t size) {
  // One small computed model per process; each input replaces its table.
  static const std::unique_ptr<Model> model =
      CreateModel("elek", Preset("atmosphere-plus"), {{"size", "4x8x4"}, {"orders", "1"}});
  auto& elek = dynamic_cast<ElekModel&>(*model);
  const std::string_view text = Text(data, size);
  const std::size_t separator = text.find(kElekRawSeparator);
  const fs::path name = ScratchFolder() / "table";
  WriteBytes(name.string() + ".json", text.substr(0, separator));
  WriteBytes(name.string() + ".raw",
             separator == std::string_view::npos ? std::string_view() : text.substr(separator + kElekRawSeparator.size()));
  return Refusable([&] {
    LoadElekTable(name.string(), elek);
    const glm::ivec3 s = elek.settings().size;
    Require(elek.Rgba(0).size() == 4u * s.x * s.y * s.z, "a loaded table of the wrong size");
  });
}

int FuzzGridCsv(const std::uint8_t* data, std::size_t size) {
  return Refusable([&] {
    for (const cli::SamplePoint& point : cli::ParseGrid(Text(data, size), "grid.csv")) {
      try {
        cli::CheckPoint(point, "");
      } catch (const Error& e) {
        throw FuzzInvariantError(std::string("an accepted point fails CheckPoint: ") + e.what());
      }
      Require(!point.location.empty(), "a point without its line");
    }
  });
}

int FuzzExrReader(const std::uint8_t* data, std::size_t size) {
  const fs::path path = ScratchFolder() / "image.exr";
  WriteBytes(path, Text(data, size));
  return Refusable([&] {
    ImageMetadata metadata;
    const Image image = ReadExr(path, &metadata);
    const std::size_t pixels = static_cast<std::size_t>(image.width) * static_cast<std::size_t>(image.height);
    Require(image.width > 0 && image.height > 0 && image.channels > 0, "an accepted image without pixels");
    Require(image.pixels.size() == pixels * static_cast<std::size_t>(image.channels), "pixels of the wrong size");
    Require(image.channel_names.size() == static_cast<std::size_t>(image.channels), "channel names of the wrong count");
    Require(image.alpha.empty() || image.alpha.size() == pixels, "alpha of the wrong size");
  });
}

int FuzzHillaireTable(const std::uint8_t* data, std::size_t size) {
  std::string_view rest = Text(data, size);
  const fs::path name = ScratchFolder() / "sky";
  const HillaireTableFiles files = HillaireTableFilesFor(name);
  std::size_t separator = rest.find(kRawSeparator);
  WriteBytes(files.json, rest.substr(0, separator));
  rest = separator == std::string_view::npos ? std::string_view() : rest.substr(separator + kRawSeparator.size());
  bool more = separator != std::string_view::npos;
  for (const fs::path& raw : files.raw) {
    // Each table's bytes up to the next separator; the tables after the last one: empty files.
    separator = rest.find(kRawSeparator);
    WriteBytes(raw, more ? rest.substr(0, separator) : std::string_view());
    more = more && separator != std::string_view::npos;
    rest = more ? rest.substr(separator + kRawSeparator.size()) : std::string_view();
  }
  return Refusable([&] {
    const HillaireTables tables = ReadHillaireTables(name);
    Require(tables.tables.size() == std::size(kHillaireTableNames), "a loaded set without its six tables");
    const std::size_t batches = ChannelBatchCount(tables.parameters.channel_count());
    for (std::size_t i = 0; i < tables.tables.size(); ++i) {
      const ExportedTable& t = tables.tables[i];
      Require(t.name == kHillaireTableNames[i], "table " + std::to_string(i) + " is '" + t.name + "'");
      Require(t.width >= 1 && t.height >= 1 && t.depth >= 1, "table " + t.name + " without texels");
      Require(t.batches == batches, "table " + t.name + " with batches other than its parameters'");
      Require(t.rgb.size() == 3 * t.texel_count() * t.batches, "table " + t.name + " of the wrong size");
      Require(i >= 4 || t.depth == 1, "2D table " + t.name + " with a depth");
    }
    const auto same_sides = [](const ExportedTable& a, const ExportedTable& b) {
      return a.width == b.width && a.height == b.height && a.depth == b.depth;
    };
    Require(same_sides(tables.table("sky_view"), tables.table("sky_view_ground")), "sky views of two sizes");
    const ExportedTable& aerial = tables.table("aerial_radiance");
    Require(same_sides(aerial, tables.table("aerial_transmittance")), "aerial tables of two sizes");
    Require(aerial.width == tables.view.aerial.width && aerial.height == tables.view.aerial.height &&
                aerial.depth == tables.view.aerial.depth,
            "aerial tables of a size other than the view's volume");
    try {
      Validate(tables.parameters);
      ValidateHillaireExportView(tables.parameters, tables.view);
    } catch (const Error& e) {
      throw FuzzInvariantError(std::string("a loaded set with an invalid atmosphere or view: ") + e.what());
    }
  });
}

}  // namespace atmo::fuzz
