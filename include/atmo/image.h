// HDR images and their files: linear float EXR with metadata, tone-mapped 8-bit PNG.
//
// To use it:
//   atmo::Image img(1920, 1080, 3);                  // linear float, row 0 at the top
//   img.at(x, y, c) = radiance;
//   atmo::WriteExr("sky.exr", img, {{"atmo:model", "hillaire"}});
//   atmo::WritePng("sky.png", img, {atmo::ToneMapper::kExponential, /*exposure=*/10.0});
//
// Writers never leave a partial or truncated file behind: they write a temporary file beside the
// target and rename it over the target only when the write succeeded. On failure they throw
// atmo::Error ("cannot write 'path': reason") and the existing target is untouched.
#pragma once

#include <cstdint>
#include <filesystem>
#include <functional>
#include <string>
#include <utility>
#include <vector>

namespace atmo {

// The colour space of an image's channels, written into EXRs as the standard `chromaticities`
// attribute: Rec.709 primaries with the D65 white, or CIE XYZ (primaries (1, 0), (0, 1), (0, 0),
// white (1/3, 1/3)). kUnspecified writes none (per-wavelength or relative channels).
enum class ColourSpace { kUnspecified, kLinearSrgb, kCieXyz };

struct Image {
  int width = 0;
  int height = 0;
  int channels = 0;
  std::vector<float> pixels;  // interleaved, pixel (x, y) channel c at (x + y * width) * channels + c
  // Optional per-pixel coverage in [0, 1] (0 outside a fisheye's circle); empty means all 1.
  std::vector<float> alpha;
  // Optional EXR channel names, one per channel; empty means the defaults: R, G, B for 3 channels,
  // else C0..Cn-1. Monte Carlo renders name their 6 channels R, G, B, R.stderr, G.stderr, B.stderr.
  std::vector<std::string> channel_names;
  ColourSpace colour_space = ColourSpace::kUnspecified;

  Image() = default;
  Image(int w, int h, int c)
      : width(w), height(h), channels(c), pixels(static_cast<std::size_t>(w) * h * c, 0.0f) {}
  float& at(int x, int y, int c) { return pixels[(static_cast<std::size_t>(y) * width + x) * channels + c]; }
  float at(int x, int y, int c) const { return pixels[(static_cast<std::size_t>(y) * width + x) * channels + c]; }
  // Index of the channel called `name` (channel_names, or the defaults when it is empty); -1 if none.
  int ChannelIndex(const std::string& name) const;
};

// Ordered (name, value) string attributes stored in the EXR header.
using ImageMetadata = std::vector<std::pair<std::string, std::string>>;

enum class ToneMapper {
  kExponential,  // the Atmosphere Plus seed: 1 - exp(-exposure * x)
  kAces,         // ACES filmic fit (Narkowicz 2015) of exposure * x
  kNone,         // exposure * x clamped to [0, 1]
};

struct ToneMapping {
  ToneMapper op = ToneMapper::kExponential;
  double exposure = 10.0;
  double gamma = 2.2;  // display encoding: value^(1/gamma)
};

// Maps one linear value to a display value in [0, 1] (tone map, then gamma).
float ToneMapValue(float linear, const ToneMapping& mapping);
// Parses "exp" / "exponential", "aces", "none"; throws atmo::Error otherwise.
ToneMapper ParseToneMapper(const std::string& name);

// EXR: 32-bit float channels named by image.channel_names, or by default R, G, B (an image with
// other than 3 channels writes C0..Cn-1), plus A when the image has alpha; ZIP compression; each
// metadata entry as a string attribute. channel_names must be empty or one unique, non-empty name
// per channel other than "A".
void WriteExr(const std::filesystem::path& path, const Image& image, const ImageMetadata& metadata = {});
// Reads an EXR written by WriteExr; throws atmo::Error. Channels: R, G, B (or C0, C1, ... when the
// file has no R, G, B) first, then every other channel but A: those named "P.layer" for one of
// the first channels P grouped by layer, in the order of P (R.stderr, G.stderr, B.stderr), then
// the rest by name. channel_names is filled with the names read.
Image ReadExr(const std::filesystem::path& path, ImageMetadata* metadata = nullptr);
// PNG: 8-bit RGB (RGBA with alpha), tone-mapped; needs an image with 3 channels.
void WritePng(const std::filesystem::path& path, const Image& image, const ToneMapping& mapping);

// Calls write(temporary_path) and renames the temporary file onto `path`. If `write` throws, the
// temporary file is removed and the error is rethrown as atmo::Error naming `path`. Fails early,
// before calling `write`, when the target's folder does not exist or is not writable.
void WriteFileAtomically(const std::filesystem::path& path,
                         const std::function<void(const std::filesystem::path&)>& write);

}  // namespace atmo
