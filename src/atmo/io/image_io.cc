// Image files: atomic writes, float EXR (OpenEXR) and 8- or 16-bit PNG (libpng). The tone
// mapping itself is in display.cc.
//
// Contracts (see include/atmo/image.h):
// - Every writer goes through WriteFileAtomically: the format code writes a temporary file beside
//   the target and only a complete file is renamed onto it. Format code reports a failure by
//   throwing any std::exception whose what() is the bare reason; WriteFileAtomically adds
//   "cannot write 'path': ".
// - ReadExr returns the string attributes sorted by name: OpenEXR keeps a header's attributes in a
//   map, so the order in which they were written is not stored in the file.
// - Every message is one line (newlines in library messages are replaced by spaces).
#include <fcntl.h>
#include <png.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <limits>
#include <memory>
#include <regex>
#include <charconv>
#include <array>
#include <atomic>
#include <cerrno>
#include <cmath>
#include <csetjmp>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <exception>
#include <fstream>
#include <map>
#include <optional>
#include <set>
#include <stdexcept>
#include <string>
#include <system_error>
#include <tuple>
#include <utility>
#include <vector>

#include <ImfChannelList.h>
#include <ImfDoubleAttribute.h>
#include <ImfIntAttribute.h>
#include <ImfStandardAttributes.h>
#include <ImfCompression.h>
#include <ImfFrameBuffer.h>
#include <ImfHeader.h>
#include <ImfInputFile.h>
#include <ImfOutputFile.h>
#include <ImfStdIO.h>
#include <ImfStringAttribute.h>
#include <ImfThreading.h>

#include <oneapi/tbb/blocked_range.h>
#include <oneapi/tbb/parallel_for.h>
#include <oneapi/tbb/task_arena.h>

#include "io/messages.h"
#include "atmo/error.h"
#include "atmo/image.h"
#include "atmo/interrupt.h"

namespace atmo {
namespace {

namespace fs = std::filesystem;

// Checks the layout invariants of Image; returns the first violation, or nothing.
std::optional<std::string> ImageProblem(const Image& image) {
  if (image.width <= 0 || image.height <= 0) {
    return "invalid image size " + std::to_string(image.width) + "x" + std::to_string(image.height);
  }
  if (image.channels <= 0) return "invalid channel count " + std::to_string(image.channels);
  const std::size_t pixel_count = static_cast<std::size_t>(image.width) * image.height;
  const std::size_t expected = pixel_count * image.channels;
  if (image.pixels.size() != expected) {
    return "image has " + std::to_string(image.pixels.size()) + " values, expected " + std::to_string(expected) +
           " (" + std::to_string(image.width) + "x" + std::to_string(image.height) + "x" +
           std::to_string(image.channels) + ")";
  }
  if (!image.alpha.empty() && image.alpha.size() != pixel_count) {
    return "alpha has " + std::to_string(image.alpha.size()) + " values, expected " + std::to_string(pixel_count);
  }
  if (!image.channel_names.empty()) {
    if (image.channel_names.size() != static_cast<std::size_t>(image.channels)) {
      return std::to_string(image.channel_names.size()) + " channel names for " + std::to_string(image.channels) +
             " channels";
    }
    std::set<std::string> seen;
    for (const std::string& name : image.channel_names) {
      if (name.empty() || name == "A") return "invalid channel name '" + name + "'";
      if (!seen.insert(name).second) return "duplicate channel name '" + name + "'";
    }
  }
  return std::nullopt;
}

// EXR channel name of image channel c: R, G, B for an RGB image, else C0, C1, ...
std::string ExrChannelName(int channel, int channel_count) {
  if (channel_count == 3) return std::string(1, "RGB"[channel]);
  // Appending rather than "C" + to_string(...): g++ 12 -O3 gives a false -Wrestrict on the latter.
  std::string name = "C";
  name += std::to_string(channel);
  return name;
}

// Alpha in [0, 1]; NaN counts as 0 (no coverage).
float ClampAlpha(float a) { return a > 0.0f ? std::min(a, 1.0f) : 0.0f; }

// Lowbias32 (C. Wellons, "Prospecting for hash functions", 2018): a full-avalanche 32-bit mix.
std::uint32_t Hash32(std::uint32_t x) {
  x ^= x >> 16;
  x *= 0x7feb352dU;
  x ^= x >> 15;
  x *= 0x846ca68bU;
  x ^= x >> 16;
  return x;
}

// Triangular-PDF dither of pixel (x, y) channel c, in (-1, 1) codes: the sum of two independent
// uniforms in [0, 1) minus 1, each from the hash of (x, y, c). With TPDF noise of +-1 code the
// rounding error's mean and variance no longer depend on the value (Lipshitz, Wannamaker &
// Vanderkooy 1992): on average the codes equal the exact value, and gradients show no bands.
double DitherCodes(int x, int y, int c) {
  const auto u32 = [](int v) { return static_cast<std::uint32_t>(v); };
  const std::uint32_t seed = Hash32(u32(x) + Hash32(u32(y) + Hash32(u32(c))));
  constexpr double kTwoTo32 = 4294967296.0;
  const double u1 = Hash32(seed ^ 0x9e3779b9U) / kTwoTo32;
  const double u2 = Hash32(seed ^ 0x7f4a7c15U) / kTwoTo32;
  return u1 + u2 - 1.0;
}

// Code of a display value in [0, 1] at `max_code` (255 or 65535): round(max_code * v), with the
// dither `noise` (codes) added first. The noise's amplitude shrinks to the distance from either end
// of the range, so that black and white stay exact and no clamping skews the mean there.
std::uint16_t ToCode(double display_value, int max_code, double noise) {
  if (!(display_value > 0.0)) return 0;
  if (display_value >= 1.0) return static_cast<std::uint16_t>(max_code);
  const double scaled = display_value * max_code;
  const double amplitude = std::min({1.0, scaled, max_code - scaled});
  const double code = std::floor(scaled + amplitude * noise + 0.5);
  return static_cast<std::uint16_t>(std::clamp(code, 0.0, static_cast<double>(max_code)));
}

// libpng reports errors through this callback; it must not return. The message goes into the
// buffer given as the error pointer, and longjmp leaves through WritePngRows's setjmp.
constexpr std::size_t kPngMessageSize = 256;
[[noreturn]] void PngError(png_structp png, png_const_charp message) {
  char* buffer = static_cast<char*>(png_get_error_ptr(png));
  std::snprintf(buffer, kPngMessageSize, "libpng: %s", message);
  png_longjmp(png, 1);
}
void PngWarning(png_structp, png_const_charp) {}

// Writes rows of big-endian samples with libpng's full API, which (unlike the simplified one)
// writes 16-bit samples as display-encoded values and the colour chunks we ask for. Only plain
// data lives in this frame, since longjmp skips destructors. Returns false with `message` filled.
bool WritePngRows(const char* path, png_uint_32 width, png_uint_32 height, bool has_alpha, int bit_depth,
                  DisplayTransfer transfer, double gamma, png_bytep* rows, char* message) {
  std::FILE* file = std::fopen(path, "wb");
  if (file == nullptr) {
    std::snprintf(message, kPngMessageSize, "cannot create '%s': %s", path, std::strerror(errno));
    return false;
  }
  png_structp png = png_create_write_struct(PNG_LIBPNG_VER_STRING, message, PngError, PngWarning);
  png_infop info = png != nullptr ? png_create_info_struct(png) : nullptr;
  if (png == nullptr || info == nullptr) {
    png_destroy_write_struct(&png, &info);
    std::fclose(file);
    std::snprintf(message, kPngMessageSize, "libpng: out of memory");
    return false;
  }
  if (setjmp(png_jmpbuf(png))) {
    png_destroy_write_struct(&png, &info);
    std::fclose(file);
    return false;
  }
  png_init_io(png, file);
  // zlib level 1, the Sub filter on every row and run-length matching: a dithered sky is noise to
  // zlib's long-range matching, and the adaptive filter choice costs a pass per filter. Measured on
  // a 1280x720 8-bit sky (docs/performance.md, "Writing files"): libpng's default (level 6,
  // adaptive filters) ~0.5 s; level 3 adaptive 98 ms, 0.67 MB; this 27 ms, 0.55 MB. The image is
  // the same (lossless either way).
  png_set_compression_level(png, 1);
  png_set_compression_strategy(png, 3);  // Z_RLE
  png_set_filter(png, PNG_FILTER_TYPE_BASE, PNG_FILTER_SUB);
  png_set_IHDR(png, info, width, height, bit_depth, has_alpha ? PNG_COLOR_TYPE_RGB_ALPHA : PNG_COLOR_TYPE_RGB,
               PNG_INTERLACE_NONE, PNG_COMPRESSION_TYPE_DEFAULT, PNG_FILTER_TYPE_DEFAULT);
  if (transfer != DisplayTransfer::kGamma) {
    // sRGB (kSrgb encodes to it, kIdentity's values are in it), plus the gAMA 1/2.2 and cHRM that
    // readers without sRGB support fall back on.
    png_set_sRGB_gAMA_and_cHRM(png, info, PNG_sRGB_INTENT_PERCEPTUAL);
  } else {
    // gAMA is the encoding exponent (sample = linear^gAMA); the primaries are Rec.709's, white D65.
    png_set_gAMA(png, info, 1.0 / gamma);
    png_set_cHRM(png, info, 0.3127, 0.3290, 0.64, 0.33, 0.30, 0.60, 0.15, 0.06);
  }
  png_set_rows(png, info, rows);
  png_write_png(png, info, PNG_TRANSFORM_IDENTITY, nullptr);
  png_destroy_write_struct(&png, &info);
  if (std::fclose(file) != 0) {
    std::snprintf(message, kPngMessageSize, "error while writing '%s'", path);
    return false;
  }
  return true;
}

// The channels after the first ones (R, G, B or C0..), in ReadExr's order: names "P.layer" for a
// first channel P grouped by layer and in the order of P, then the others by name.
// A metadata value as an EXR attribute: a plain decimal number (the whole text, as atmo writes
// numbers: optional sign, digits, fraction, exponent) becomes a double attribute, whatever its
// value (so a reader finds one type per name; counts are exact up to 2^53); anything else a
// string. Names ending in "Hash" stay strings (identifiers that can look like numbers).
std::unique_ptr<Imf::Attribute> MetadataAttribute(const std::string& name, const std::string& value) {
  const bool identifier = name.size() >= 4 && name.compare(name.size() - 4, 4, "Hash") == 0;
  static const std::regex number(R"(-?[0-9]+(\.[0-9]+)?([eE][-+]?[0-9]+)?)");
  if (!identifier && std::regex_match(value, number)) {
    double d = 0.0;
    const auto [end, error] = std::from_chars(value.data(), value.data() + value.size(), d);
    if (error == std::errc() && end == value.data() + value.size() && std::isfinite(d)) {
      return std::make_unique<Imf::DoubleAttribute>(d);
    }
  }
  return std::make_unique<Imf::StringAttribute>(value);
}

// The text of a metadata attribute that ReadExr reports: strings as they are, numbers in the
// shortest form that reads back to the same value; other attribute types are not metadata.
std::optional<std::string> MetadataText(const Imf::Attribute& attribute) {
  if (const auto* text = dynamic_cast<const Imf::StringAttribute*>(&attribute)) return text->value();
  if (const auto* i = dynamic_cast<const Imf::IntAttribute*>(&attribute)) return std::to_string(i->value());
  if (const auto* d = dynamic_cast<const Imf::DoubleAttribute*>(&attribute)) {
    char buffer[32];
    const auto result = std::to_chars(buffer, buffer + sizeof buffer, d->value());
    return std::string(buffer, result.ptr);
  }
  return std::nullopt;
}

std::vector<std::string> OrderExtraChannels(std::vector<std::string> extras, const std::vector<std::string>& first) {
  // OpenEXR's layers: channel "LAYER.NAME" is NAME of layer LAYER (the text before the last dot).
  const auto key = [&](const std::string& name) {
    const std::size_t dot = name.rfind('.');
    if (dot != std::string::npos) {
      const auto p = std::find(first.begin(), first.end(), name.substr(dot + 1));
      if (p != first.end()) return std::make_tuple(0, name.substr(0, dot), p - first.begin(), name);
    }
    return std::make_tuple(1, std::string(), std::ptrdiff_t{0}, name);
  };
  std::sort(extras.begin(), extras.end(), [&](const std::string& a, const std::string& b) { return key(a) < key(b); });
  return extras;
}

// Whether OpenEXR reads an attribute value of `type` in exactly its declared `value.size()` bytes.
// Its readers of the known types do not follow the declared size: a box2i declared with 4 bytes
// is read as 16, a channel list is read up to its empty name, a string vector by its inner
// lengths, a preview by its width and height. The header is then read shifted from there on,
// and a later field can become a string of gigabytes (a channel list of 19 bytes declared as 73
// made a 1.9 GB string from a 249-byte file, found by fuzz_exr_reader).
std::optional<std::string> AttributeLayoutProblem(const std::string& type, const std::vector<unsigned char>& value,
                                                  std::size_t max_name) {
  static const std::pair<std::string_view, std::size_t> kFixed[] = {
      {"box2i", 16}, {"box2f", 16},    {"chromaticities", 32}, {"compression", 1}, {"double", 8},
      {"envmap", 1}, {"float", 4},     {"int", 4},             {"keycode", 28},    {"lineOrder", 1},
      {"m33f", 36},  {"m33d", 72},     {"m44f", 64},           {"m44d", 128},      {"rational", 8},
      {"tiledesc", 9}, {"timecode", 8}, {"v2i", 8},            {"v2f", 8},         {"v2d", 16},
      {"v3i", 12},   {"v3f", 12},      {"v3d", 24},            {"deepImageState", 1}};
  const std::size_t size = value.size();
  const auto u32 = [&](std::size_t at) {
    return std::uint32_t(value[at]) | std::uint32_t(value[at + 1]) << 8 | std::uint32_t(value[at + 2]) << 16 |
           std::uint32_t(value[at + 3]) << 24;
  };
  const auto declared = [&](std::size_t read) {
    return type + " of " + std::to_string(read) + " bytes declared as " + std::to_string(size);
  };
  for (const auto& [name, bytes] : kFixed) {
    if (type == name) return size == bytes ? std::nullopt : std::optional<std::string>(declared(bytes));
  }
  if (type == "chlist") {
    std::size_t at = 0;
    while (true) {
      const std::size_t start = at;
      while (at < size && value[at] != 0) ++at;
      if (at >= size) return "a channel list without its end";
      if (at - start > max_name) return "a channel name longer than " + std::to_string(max_name) + " bytes";
      if (at == start) break;  // the empty name that ends the list
      at += 17;                // the NUL, pixel type, pLinear and reserved, x and y sampling
    }
    if (at + 1 != size) return declared(at + 1);
  } else if (type == "stringvector") {
    for (std::size_t at = 0; at < size;) {
      if (at + 4 > size || u32(at) > size - at - 4) return "a string vector whose strings overrun its " + std::to_string(size) + " bytes";
      at += 4 + u32(at);
    }
  } else if (type == "preview") {
    if (size < 8 || (std::uint64_t{u32(0)} * u32(4) * 4 + 8) != size) return "a preview image of another size than declared";
  } else if (type == "idmanifest") {
    return std::string("an ID manifest (atmo reads none)");
  }
  return std::nullopt;
}

// The sizes an EXR header declares, checked before OpenEXR reads it: OpenEXR 3.1 allocates
// what the header says before it finds that the file is shorter (found by fuzz_exr_reader): an
// attribute of a declared 1.7 GB, line-offset tables and line buffers for a data window of 2^31
// pixels. Walks the header (magic, version, then per attribute name\0 type\0 int32 size value,
// up to an empty name; every part of a multi-part file) and returns the first problem: an
// attribute longer than the rest of the file, or a data window (or tile) whose pixels,
// uncompressed, would take more than kMaxCompressionRatio times the file's bytes. A header that
// cannot be walked (a name beyond 255 bytes, or 31 without the long-names flag; cut off) is a problem too: OpenEXR would read it
// differently.
std::optional<std::string> ExrHeaderProblem(const fs::path& path) {
  // zlib (ZIP, PXR24) compresses at most ~1032:1, RLE 64:1.
  constexpr std::int64_t kMaxCompressionRatio = 2048;
  std::ifstream in(path, std::ios::binary);
  std::error_code ec;
  const std::int64_t file_bytes = static_cast<std::int64_t>(fs::file_size(path, ec));
  if (!in || ec) return std::nullopt;  // OpenEXR reports what is wrong
  const auto read_u32 = [&](std::uint32_t& value) {
    unsigned char b[4];
    if (!in.read(reinterpret_cast<char*>(b), 4)) return false;
    value = std::uint32_t(b[0]) | std::uint32_t(b[1]) << 8 | std::uint32_t(b[2]) << 16 | std::uint32_t(b[3]) << 24;
    return true;
  };
  std::size_t max_name = 255;  // 31 without the long-names flag (OpenEXR reads no more)
  const auto read_name = [&](std::string& name) {
    name.clear();
    char c;
    while (in.get(c)) {
      if (c == '\0') return true;
      if (name.size() >= max_name) return false;
      name += c;
    }
    return false;
  };
  std::uint32_t magic = 0, version = 0;
  if (!read_u32(magic) || !read_u32(version) || magic != 20000630u) return std::nullopt;
  const bool multipart = (version & 0x1000u) != 0;
  if ((version & 0x400u) == 0) max_name = 31;
  for (int part = 0;; ++part) {
    std::int64_t width = 0, height = 0, bytes_per_pixel = 0, tile_x = 0, tile_y = 0;
    int attributes = 0;
    std::string name, type;
    while (true) {
      if (!read_name(name)) return std::string("a name longer than " + std::to_string(max_name) + " bytes, or cut off");
      if (name.empty()) break;
      std::uint32_t size = 0;
      if (!read_name(type) || !read_u32(size)) {
        return "attribute '" + OneLine(name) + "' without its type or size (a type name too long, or cut off)";
      }
      const std::int64_t remaining = file_bytes - static_cast<std::int64_t>(in.tellg());
      if (static_cast<std::int64_t>(static_cast<std::int32_t>(size)) < 0 || std::int64_t{size} > remaining) {
        return "attribute '" + OneLine(name) + "' declares " + std::to_string(static_cast<std::int32_t>(size)) +
               " bytes, more than the " + std::to_string(remaining) + " left in the file";
      }
      std::vector<unsigned char> value(size);
      if (!in.read(reinterpret_cast<char*>(value.data()), size)) return "attribute '" + OneLine(name) + "' cut off";
      if (auto problem = AttributeLayoutProblem(type, value, max_name)) {
        return "attribute '" + OneLine(name) + "': " + *problem;
      }
      const auto i32 = [&](std::size_t at) {
        return static_cast<std::int32_t>(std::uint32_t(value[at]) | std::uint32_t(value[at + 1]) << 8 |
                                         std::uint32_t(value[at + 2]) << 16 | std::uint32_t(value[at + 3]) << 24);
      };
      if (name == "dataWindow" && type == "box2i" && size == 16) {
        width = std::int64_t{i32(8)} - i32(0) + 1;
        height = std::int64_t{i32(12)} - i32(4) + 1;
      } else if (name == "tiles" && type == "tiledesc" && size >= 8) {
        tile_x = static_cast<std::uint32_t>(i32(0));
        tile_y = static_cast<std::uint32_t>(i32(4));
      } else if (name == "channels" && type == "chlist") {
        // name\0, int32 pixel type (0 uint, 1 half, 2 float), 4 bytes, int32 x and y sampling.
        for (std::size_t at = 0; at < value.size() && value[at] != 0;) {
          const std::size_t start = at;
          while (at < value.size() && value[at] != 0) ++at;
          if (at + 17 > value.size()) break;
          bytes_per_pixel += i32(at + 1) == 1 ? 2 : 4;
          // Subsampled channels are refused below anyway; OpenEXR sized its buffers by a huge
          // sampling before that (1.9 GB for a 249-byte file, found by fuzz_exr_reader).
          if (i32(at + 9) != 1 || i32(at + 13) != 1) {
            return "channel '" + OneLine(std::string(value.begin() + start, value.begin() + at)) + "' has sampling " +
                   std::to_string(i32(at + 9)) + "x" + std::to_string(i32(at + 13)) + "; atmo reads only 1x1";
          }
          at += 17;
        }
      }
      if (++attributes > 100000) return std::string("more than 100000 attributes");
    }
    if (attributes == 0) break;                               // the empty header ending a multi-part list
    const std::int64_t limit = kMaxCompressionRatio * (file_bytes + 4096) / std::max<std::int64_t>(bytes_per_pixel, 1);
    if (width > 0 && height > 0 && (width > limit || height > limit || width * height > limit)) {
      return "declares " + std::to_string(width) + "x" + std::to_string(height) + " pixels, more than its " +
             std::to_string(file_bytes) + " bytes can hold";
    }
    if (tile_x > limit || tile_y > limit || tile_x * tile_y > limit) {
      return "declares tiles of " + std::to_string(tile_x) + "x" + std::to_string(tile_y) + " pixels, more than its " +
             std::to_string(file_bytes) + " bytes can hold";
    }
    if (!multipart) break;
  }
  return std::nullopt;
}

}  // namespace

int Image::ChannelIndex(const std::string& name) const {
  for (int c = 0; c < channels; ++c) {
    const std::string own = channel_names.empty() ? ExrChannelName(c, channels) : channel_names[c];
    if (own == name) return c;
  }
  return -1;
}

// ---------------------------------------------------------------------------------------------
// Tone mapper names.

ToneMapper ParseToneMapper(const std::string& name) {
  if (name == "exp" || name == "exponential") return ToneMapper::kExponential;
  if (name == "aces") return ToneMapper::kAces;
  if (name == "none") return ToneMapper::kNone;
  if (name == "agx") return ToneMapper::kAgx;
  throw Error("unknown tone mapper '" + OneLine(name) + "' (use agx, exp, aces or none)");
}

Metering ParseMetering(const std::string& name) {
  if (name == "adaptive") return Metering::kAdaptive;
  if (name == "camera") return Metering::kCamera;
  throw Error("unknown metering '" + OneLine(name) + "' (use adaptive or camera)");
}


// ---------------------------------------------------------------------------------------------
// EXR.

void WriteExr(const fs::path& path, const Image& image, const ImageMetadata& metadata, AtomicFileSet* set) {
  if (auto problem = ImageProblem(image)) throw Error(WriteError(path, *problem));

  // Build the header before touching the file system, so that bad metadata creates nothing.
  Imf::Header header(image.width, image.height);
  // ZIP (lossless, 16 scanlines a block, read by every EXR reader) at zlib level 1 on OpenEXR's
  // thread pool, one thread a core of the current oneTBB arena (--threads). Measured on a
  // 1280x720 RGB float sky on 2 cores (docs/performance.md, "Writing files"): level 6 on one
  // thread 269 ms, 5.71 MB; level 1 on 2 threads 106 ms, 5.88 MB; PIZ 175 ms, 4.85 MB.
  header.compression() = Imf::ZIP_COMPRESSION;
  header.zipCompressionLevel() = 1;
  std::vector<std::string> names;
  for (int c = 0; c < image.channels; ++c) {
    names.push_back(image.channel_names.empty() ? ExrChannelName(c, image.channels) : image.channel_names[c]);
  }
  for (const std::string& name : names) header.channels().insert(name, Imf::Channel(Imf::FLOAT));
  if (!image.alpha.empty()) header.channels().insert("A", Imf::Channel(Imf::FLOAT));
  if (image.colour_space == ColourSpace::kLinearSrgb) {
    Imf::addChromaticities(header, Imf::Chromaticities());  // OpenEXR's default: Rec.709, D65
  } else if (image.colour_space == ColourSpace::kCieXyz) {
    Imf::addChromaticities(header, Imf::Chromaticities(Imath::V2f(1.0f, 0.0f), Imath::V2f(0.0f, 1.0f),
                                                       Imath::V2f(0.0f, 0.0f), Imath::V2f(1.0f / 3.0f, 1.0f / 3.0f)));
  }
  // The standard `envmap` attribute of an environment map (atmo/cubemap.h, docs/environment.md).
  if (image.envmap == EnvMap::kLatLong) Imf::addEnvmap(header, Imf::ENVMAP_LATLONG);
  if (image.envmap == EnvMap::kCube) Imf::addEnvmap(header, Imf::ENVMAP_CUBE);
  std::set<std::string> seen;
  for (const auto& [name, value] : metadata) {
    if (name.empty()) throw Error(WriteError(path, "metadata with an empty name"));
    if (!seen.insert(name).second) throw Error(WriteError(path, "duplicate metadata name '" + name + "'"));
    try {
      header.insert(name, *MetadataAttribute(name, value));
    } catch (const std::exception& e) {
      // e.g. a name that is a standard attribute of another type ("channels").
      throw Error(WriteError(path, "metadata '" + name + "': " + e.what()));
    }
  }

  const auto write = [&](const fs::path& temporary) {
    std::ofstream stream(temporary, std::ios::binary | std::ios::trunc);
    if (!stream) throw std::runtime_error("cannot create '" + temporary.string() + "'");
    {
      Imf::StdOFStream exr_stream(stream, temporary.c_str());
      const int threads = std::max(1, oneapi::tbb::this_task_arena::max_concurrency());
      if (Imf::globalThreadCount() != threads) Imf::setGlobalThreadCount(threads);
      Imf::OutputFile file(exr_stream, header, threads);
      Imf::FrameBuffer frame;
      const std::size_t x_stride = sizeof(float) * image.channels;
      const std::size_t y_stride = x_stride * image.width;
      const Imath::Box2i window = header.dataWindow();
      for (int c = 0; c < image.channels; ++c) {
        frame.insert(names[c], Imf::Slice::Make(Imf::FLOAT, image.pixels.data() + c, window, x_stride, y_stride));
      }
      if (!image.alpha.empty()) {
        frame.insert("A", Imf::Slice::Make(Imf::FLOAT, image.alpha.data(), window, sizeof(float),
                                           sizeof(float) * image.width));
      }
      file.setFrameBuffer(frame);
      file.writePixels(image.height);
    }  // ~OutputFile writes the line-offset table.
    stream.close();
    if (!stream) throw std::runtime_error("error while writing '" + temporary.string() + "'");
  };
  if (set != nullptr) {
    set->Stage(path, write);
  } else {
    WriteFileAtomically(path, write);
  }
}

Image ReadExr(const fs::path& path, ImageMetadata* metadata) {
  std::error_code ec;
  const fs::file_status status = fs::status(path, ec);
  if (!fs::exists(status)) throw Error(ReadError(path, "no such file"));
  if (fs::is_directory(status)) throw Error(ReadError(path, "is a directory"));
  // OpenEXR would open a FIFO and wait for a writer, and read a device forever.
  if (!fs::is_regular_file(status)) throw Error(ReadError(path, "is not a regular file (a device, FIFO or socket)"));
  if (auto problem = ExrHeaderProblem(path)) throw Error(ReadError(path, "corrupt header: " + *problem));
  try {
    Imf::InputFile file(path.c_str());
    const Imf::Header& header = file.header();
    const Imath::Box2i window = header.dataWindow();
    const std::int64_t width = std::int64_t{window.max.x} - window.min.x + 1;
    const std::int64_t height = std::int64_t{window.max.y} - window.min.y + 1;
    if (width <= 0 || height <= 0) throw Error(ReadError(path, "empty data window"));

    // Channels: R, G, B if present, else C0, C1, ... up to the first missing index.
    const Imf::ChannelList& list = header.channels();
    std::vector<std::string> names;
    if (list.findChannel("R") && list.findChannel("G") && list.findChannel("B")) {
      names = {"R", "G", "B"};
    } else if (list.findChannel("X") && list.findChannel("Y") && list.findChannel("Z")) {
      names = {"X", "Y", "Z"};
    } else {
      for (int c = 0;; ++c) {
        std::string name = ExrChannelName(c, /*channel_count=*/0);  // C0, C1, ...
        if (!list.findChannel(name)) break;
        names.push_back(std::move(name));
      }
    }
    if (names.empty()) throw Error(ReadError(path, "no R, G, B, X, Y, Z or C0.. channels"));
    std::vector<std::string> extras;
    for (auto it = list.begin(); it != list.end(); ++it) {
      const std::string name = it.name();
      if (name != "A" && std::find(names.begin(), names.end(), name) == names.end()) extras.push_back(name);
    }
    for (std::string& name : OrderExtraChannels(std::move(extras), names)) names.push_back(std::move(name));
    for (const std::string& name : names) {
      const Imf::Channel* channel = list.findChannel(name);
      if (channel->xSampling != 1 || channel->ySampling != 1) {
        throw Error(ReadError(path, "subsampled channel '" + name + "'"));
      }
    }
    const bool has_alpha = list.findChannel("A") != nullptr;

    // Refuse sizes that cannot be allocated sensibly (a corrupt or hostile header).
    constexpr std::int64_t kMaxValues = std::int64_t{1} << 32;
    if (width > kMaxValues / height || width * height > kMaxValues / static_cast<std::int64_t>(names.size() + 1)) {
      throw Error(ReadError(path, "image too large (" + std::to_string(width) + "x" + std::to_string(height) + ")"));
    }
    Image image(static_cast<int>(width), static_cast<int>(height), static_cast<int>(names.size()));
    if (has_alpha) image.alpha.assign(static_cast<std::size_t>(width * height), 0.0f);
    Imf::FrameBuffer frame;
    const std::size_t x_stride = sizeof(float) * image.channels;
    const std::size_t y_stride = x_stride * image.width;
    for (int c = 0; c < image.channels; ++c) {
      frame.insert(names[c], Imf::Slice::Make(Imf::FLOAT, image.pixels.data() + c, window, x_stride, y_stride));
    }
    if (has_alpha) {
      frame.insert("A", Imf::Slice::Make(Imf::FLOAT, image.alpha.data(), window, sizeof(float),
                                         sizeof(float) * image.width));
    }
    file.setFrameBuffer(frame);
    file.readPixels(window.min.y, window.max.y);
    image.channel_names = names;
    if (Imf::hasChromaticities(header)) {
      const Imf::Chromaticities& c = Imf::chromaticities(header);
      image.colour_space = c.red.x == 1.0f && c.green.y == 1.0f ? ColourSpace::kCieXyz : ColourSpace::kLinearSrgb;
    }
    if (Imf::hasEnvmap(header)) {
      image.envmap = Imf::envmap(header) == Imf::ENVMAP_CUBE ? EnvMap::kCube : EnvMap::kLatLong;
    }

    if (metadata != nullptr) {
      metadata->clear();
      for (auto it = header.begin(); it != header.end(); ++it) {
        // atmo's numbers come back as the text it wrote; the standard attributes (floats,
        // vectors, boxes, chromaticities, envmap) are not metadata.
        if (std::optional<std::string> text = MetadataText(it.attribute())) metadata->emplace_back(it.name(), *text);
      }
    }
    return image;
  } catch (const Error&) {
    throw;
  } catch (const std::exception& e) {
    throw Error(ReadError(path, e.what()));
  }
}

// ---------------------------------------------------------------------------------------------
// PNG.

void WritePng(const fs::path& path, const Image& image, const ToneMapping& mapping) {
  if (auto problem = ImageProblem(image)) throw Error(WriteError(path, *problem));
  if (image.channels != 3) {
    throw Error(WriteError(path, "PNG needs a 3-channel image, got " + std::to_string(image.channels)));
  }
  if (!std::isfinite(mapping.exposure) || !(mapping.gamma > 0.0) || !std::isfinite(mapping.gamma)) {
    throw Error(WriteError(path, "invalid tone mapping (exposure must be finite, gamma > 0)"));
  }
  if (mapping.bit_depth != 8 && mapping.bit_depth != 16) {
    throw Error(WriteError(path, "invalid PNG bit depth " + std::to_string(mapping.bit_depth) + " (use 8 or 16)"));
  }

  const bool has_alpha = !image.alpha.empty();
  const int out_channels = has_alpha ? 4 : 3;
  const int bytes_per_sample = mapping.bit_depth / 8;
  const int max_code = (1 << mapping.bit_depth) - 1;
  const std::size_t row_bytes = static_cast<std::size_t>(image.width) * out_channels * bytes_per_sample;
  std::vector<png_byte> bytes(row_bytes * image.height);
  const auto put = [&](png_byte* at, std::uint16_t code) {
    if (bytes_per_sample == 2) {
      at[0] = static_cast<png_byte>(code >> 8);  // PNG samples are big-endian
      at[1] = static_cast<png_byte>(code & 0xff);
    } else {
      at[0] = static_cast<png_byte>(code);
    }
  };
  // Rows in parallel: each pixel's codes depend on that pixel alone (the dither on x, y, c).
  using Rows = oneapi::tbb::blocked_range<int>;
  oneapi::tbb::parallel_for(Rows(0, image.height), [&](const Rows& range) {
    for (int y = range.begin(); y != range.end(); ++y) {
      for (int x = 0; x < image.width; ++x) {
        const std::size_t i = static_cast<std::size_t>(y) * image.width + x;
        const float* p = image.pixels.data() + i * 3;
        const std::array<float, 3> display = ToneMapPixel(p[0], p[1], p[2], mapping);
        png_byte* out = bytes.data() + i * out_channels * bytes_per_sample;
        for (int c = 0; c < 3; ++c) {
          const double noise = mapping.dither ? DitherCodes(x, y, c) : 0.0;
          put(out + c * bytes_per_sample, ToCode(display[c], max_code, noise));
        }
        if (has_alpha) put(out + 3 * bytes_per_sample, ToCode(ClampAlpha(image.alpha[i]), max_code, 0.0));
      }
    }
  });
  std::vector<png_bytep> rows(image.height);
  for (int y = 0; y < image.height; ++y) rows[y] = bytes.data() + y * row_bytes;

  WriteFileAtomically(path, [&](const fs::path& temporary) {
    char message[kPngMessageSize] = "";
    if (!WritePngRows(temporary.c_str(), static_cast<png_uint_32>(image.width), static_cast<png_uint_32>(image.height),
                      has_alpha, mapping.bit_depth, mapping.transfer, mapping.gamma, rows.data(), message)) {
      throw std::runtime_error(message);
    }
  });
}

// ---------------------------------------------------------------------------------------------
// Radiance HDR (RGBE).

void WriteRadianceHdr(const fs::path& path, const Image& image) {
  if (auto problem = ImageProblem(image)) throw Error(WriteError(path, *problem));
  if (image.channels != 3) {
    throw Error(WriteError(path, "Radiance HDR needs a 3-channel image, got " + std::to_string(image.channels)));
  }
  std::string bytes = "#?RADIANCE\n# atmo " ATMO_VERSION "\nFORMAT=32-bit_rle_rgbe\n\n-Y " +
                      std::to_string(image.height) + " +X " + std::to_string(image.width) + "\n";
  const std::size_t header = bytes.size();
  bytes.resize(header + 4 * static_cast<std::size_t>(image.width) * image.height);
  for (std::size_t i = 0; i < static_cast<std::size_t>(image.width) * image.height; ++i) {
    double rgb[3];
    for (int c = 0; c < 3; ++c) {
      const double v = image.pixels[3 * i + c];
      rgb[c] = v > 0.0 ? std::min(v, 1.7e38) : 0.0;  // NaN and negative values as 0
    }
    const double largest = std::max({rgb[0], rgb[1], rgb[2]});
    unsigned char* out = reinterpret_cast<unsigned char*>(bytes.data()) + header + 4 * i;
    if (largest < 1e-32) {
      out[0] = out[1] = out[2] = out[3] = 0;
      continue;
    }
    // largest = m 2^e with m in [0.5, 1): mantissa bytes v 256 / 2^e, exponent byte e + 128.
    int exponent = 0;
    const double mantissa = std::frexp(largest, &exponent);
    const double scale = mantissa * 256.0 / largest;
    for (int c = 0; c < 3; ++c) out[c] = static_cast<unsigned char>(std::min(255.0, rgb[c] * scale));
    out[3] = static_cast<unsigned char>(exponent + 128);
  }
  WriteFileAtomically(path, [&](const fs::path& temporary) {
    std::ofstream file(temporary, std::ios::binary | std::ios::trunc);
    file.write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
    file.close();
    if (!file) throw std::runtime_error("write failed");
  });
}

}  // namespace atmo
