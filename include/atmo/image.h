// HDR images and their files: linear float EXR with metadata, tone-mapped 8- or 16-bit PNG.
//
// To use it:
//   atmo::Image img(1920, 1080, 3);                  // linear float, row 0 at the top
//   img.at(x, y, c) = radiance;
//   atmo::WriteExr("sky.exr", img, {{"atmo:model", "hillaire"}});
//   atmo::WritePng("sky.png", img, {atmo::ToneMapper::kExponential, /*exposure=*/10.0});
//   atmo::ToneMapping auto_exposed;                // luminance curve, sRGB, dithered 8 bits
//   auto_exposed.exposure = atmo::ExposureFromEv100(atmo::AutoExposureEv100(img));
//   atmo::WritePng("auto.png", img, auto_exposed);
//
// Writers never leave a partial or truncated file behind: they write a temporary file beside the
// target and rename it over the target only when the write succeeded. On failure they throw
// atmo::Error ("cannot write 'path': reason") and the existing target is untouched.
#pragma once

#include <array>
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

// What an EXR says its image is as an environment map, as OpenEXR's standard `envmap` attribute
// (ImfEnvmap.h): none, ENVMAP_LATLONG (an equirect) or ENVMAP_CUBE (six faces stacked vertically,
// atmo/cubemap.h). docs/environment.md relates both to atmo's frame.
enum class EnvMap { kNone, kLatLong, kCube };

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
  EnvMap envmap = EnvMap::kNone;  // written by WriteExr as the `envmap` attribute, read by ReadExr

  Image() = default;
  Image(int w, int h, int c)
      : width(w), height(h), channels(c), pixels(static_cast<std::size_t>(w) * h * c, 0.0f) {}
  float& at(int x, int y, int c) { return pixels[(static_cast<std::size_t>(y) * width + x) * channels + c]; }
  float at(int x, int y, int c) const { return pixels[(static_cast<std::size_t>(y) * width + x) * channels + c]; }
  // Index of the channel called `name` (channel_names, or the defaults when it is empty); -1 if none.
  int ChannelIndex(const std::string& name) const;
};

// Ordered (name, value) attributes of the EXR header: a value that is a plain decimal number is
// stored as a double attribute (except names ending in "Hash"), any other as a string; ReadExr
// gives numbers back in the shortest text that reads back to the same double.
using ImageMetadata = std::vector<std::pair<std::string, std::string>>;

enum class ToneMapper {
  kExponential,  // the Atmosphere Plus seed: 1 - exp(-exposure * x)
  kAces,         // ACES filmic fit (Narkowicz 2015) of exposure * x
  kNone,         // exposure * x clamped to [0, 1]
  // AgX (Sobotka 2022, the view transform of Blender 4): each channel of exposure * x, in a space
  // inset towards white, through a log2 encoding of 16.5 stops and a sigmoid that puts scene grey
  // 0.18 at display 0.5; bright colours roll off to white. Always per channel (docs/display.md).
  kAgx,
};

// Display encoding of a tone-mapped value v in [0, 1].
enum class DisplayTransfer {
  kSrgb,   // IEC 61966-2-1: 12.92 v for v <= 0.0031308, else 1.055 v^(1/2.4) - 0.055
  kGamma,  // the bare power v^(1/gamma) of the seed
  // None: the values are display-referred sRGB already (charts, false-colour maps), written as
  // they are and tagged sRGB. With kNone, exposure 1 and per_channel, a plain clamp-and-round.
  kIdentity,
};

// Linear RGB to display values. The linear values are Rec.709/sRGB (D65) primaries; their
// luminance (Luminance below) is in cd/m^2 for physical presets, relative for the legacy ones: the
// mapping does not care, `exposure` scales either into the curve's range (see ExposureFromEv100).
struct ToneMapping {
  ToneMapper op = ToneMapper::kAgx;
  double exposure = 10.0;  // multiplier of the linear values before the curve
  double gamma = 2.2;      // > 0; the power of DisplayTransfer::kGamma (unused by kSrgb)
  // false: the curve maps the luminance Y and the pixel is scaled by T(Y)/Y, then divided by its
  // largest channel when that exceeds 1, so hue and saturation survive (ToneMapPixel).
  // true: the curve maps each channel on its own (the seed's look; bright colours go to white).
  // kAgx ignores it: AgX is a per-channel transform in its own inset space.
  bool per_channel = false;
  DisplayTransfer transfer = DisplayTransfer::kSrgb;
  // PNG only: add a triangular-PDF dither of at most +-1 code before rounding to the code (a
  // deterministic hash of x, y and channel, so files are reproducible). Removes banding.
  bool dither = true;
  int bit_depth = 8;  // PNG only: 8 or 16 bits per channel
};

// What WritePng did before physical units: per-channel curve, bare gamma, no dither, 8 bits.
ToneMapping SeedToneMapping(ToneMapper op = ToneMapper::kExponential, double exposure = 10.0, double gamma = 2.2);

// Luminance of linear Rec.709 RGB (ITU-R BT.709, D65): 0.2126 R + 0.7152 G + 0.0722 B.
double Luminance(double r, double g, double b);

// Exposure value at ISO 100, the photographic convention of Lagarde & de Rousiers 2014 ("Moving
// Frostbite to PBR", section 5.1). A camera of f-number N, exposure time t and saturation-based
// sensitivity S saturates at the luminance L_max = 78 / (0.65 S) * N^2 / t cd/m^2; at S = 100,
// where EV100 = log2(N^2 / t), that is L_max = 1.2 * 2^EV100, and the exposure multiplier that maps
// L_max to 1 is 1 / (1.2 * 2^EV100). EV100 15 is a sunny day (L_max about 39000 cd/m^2).
double ExposureFromEv100(double ev100);
// The inverse: log2(1 / (1.2 * exposure)); NaN for exposure <= 0.
double Ev100FromExposure(double exposure);
// EV100 for the image from L_avg, the log-average (geometric mean) luminance of channels 0..2
// as linear RGB. Pixels with alpha 0, and non-finite or non-positive luminance, are skipped. So that
// a small, very bright sun disc (or a few black pixels) does not set the exposure, each log2
// luminance is first clamped to the image's 2nd..98th percentile (a winsorised mean); a sun
// that fills more than 2% of the frame does count. An image with no usable pixel gives 0. Throws
// atmo::Error for fewer than 3 channels or an inconsistent image.
//
// How the average is placed (Metering):
// - kAdaptive (default): at MeteringKey(L_avg), so that a noon sky is exposed as the sunny-16 rule
//   exposes daylight and a twilight or night sky darker, as the eye's adaptation falls short:
//   EV100 = log2(L_avg / (1.2 * key)). The luminance must be in cd/m^2.
// - kCamera: a reflected-light meter (K = 12.5, S = 100): EV100 = log2(L_avg * S / K), the average
//   at 1 / 9.6 of L_max whatever its level (every sky a mid grey). For relative units too.
enum class Metering { kAdaptive, kCamera };
double AutoExposureEv100(const Image& image, Metering metering = Metering::kAdaptive);
// The EV100 of AutoExposureEv100 from its statistic, the winsorised mean of log2 L (L in cd/m^2
// for kAdaptive): for meters that compute the statistic elsewhere (the GPU's, gl/exposure_gl.h).
double MeteredEv100(double log2_average_luminance, Metering metering = Metering::kAdaptive);
// The key (the exposed value of the average luminance, 0.18 being Reinhard's "normal" key) for an
// average luminance L in cd/m^2: 1.03 - 2 / (2 + log10(L + 1)) (Krawczyk, Myszkowski and Seidel
// 2005, "Perceptual effects in real-time tone mapping", SCCG 2005, eq. 11), clamped below at 0.01.
// About 0.69 at a noon sky of 7000 cd/m^2, 0.31 at 5 cd/m^2, 0.04 at 0.05 cd/m^2.
double AdaptationKey(double average_luminance);
// The key of Metering::kAdaptive: AdaptationKey scaled so that a clear daylight sky's average
// (7000 cd/m^2) lands at 0.18, the mid grey of the display transforms (AgX maps it to 0.5):
// 0.18 * a(L) / a(7000). A noon sky then gets EV100 ~ 15, the sunny-16 rule; 40 cd/m^2 (civil
// twilight) 0.125, 1 cd/m^2 (nautical) 0.042, 10^-3 cd/m^2 and less (night) 0.0079.
double MeteringKey(double average_luminance);
// Parses "adaptive" or "camera"; throws atmo::Error otherwise.
Metering ParseMetering(const std::string& name);

// sRGB transfer function (IEC 61966-2-1) of a linear value in [0, 1] (clamped), and its inverse.
double SrgbEncode(double linear);
double SrgbDecode(double encoded);
// mapping.transfer applied to a value in [0, 1] (clamped; NaN gives 0).
double EncodeDisplay(double linear, const ToneMapping& mapping);

// Maps one linear value to a display value in [0, 1]: exposure, curve, clamp, display encoding.
// It is one channel of the per-channel mode, and every channel of a grey pixel in either mode.
float ToneMapValue(float linear, const ToneMapping& mapping);
// Maps one linear RGB pixel to display values in [0, 1] as mapping.per_channel says. NaN and
// negative channels count as 0, +inf as the largest float.
std::array<float, 3> ToneMapPixel(float r, float g, float b, const ToneMapping& mapping);
// AgX's output for one exposed linear Rec.709 pixel, display-encoded for a 2.2 power display, in
// [0, 1] (ToneMapPixel decodes it and applies mapping.transfer).
std::array<double, 3> AgxDisplay(double r, double g, double b);
// Parses "exp" / "exponential", "aces", "none", "agx"; throws atmo::Error otherwise.
ToneMapper ParseToneMapper(const std::string& name);

// EXR: 32-bit float channels named by image.channel_names, or by default R, G, B (an image with
// other than 3 channels writes C0..Cn-1), plus A when the image has alpha; ZIP compression; each
// metadata entry as a double or string attribute (ImageMetadata). channel_names must be empty or one unique, non-empty name
// per channel other than "A".
// With `set`, the file is staged there (AtomicFileSet below) and appears on its Commit.
class AtomicFileSet;
void WriteExr(const std::filesystem::path& path, const Image& image, const ImageMetadata& metadata = {},
              AtomicFileSet* set = nullptr);
// Reads an EXR written by WriteExr; throws atmo::Error. Channels: R, G, B (or C0, C1, ... when the
// file has no R, G, B) first, then every other channel but A: those named "P.layer" for one of
// the first channels P grouped by layer, in the order of P (R.stderr, G.stderr, B.stderr), then
// the rest by name. channel_names is filled with the names read.
Image ReadExr(const std::filesystem::path& path, ImageMetadata* metadata = nullptr);
// PNG: RGB (RGBA with alpha) of mapping.bit_depth bits, tone-mapped by ToneMapPixel, optionally
// dithered; alpha is rounded, never dithered. Carries its colour space: an sRGB chunk (with the
// matching gAMA and cHRM) for DisplayTransfer::kSrgb and kIdentity, for kGamma gAMA 1/gamma and
// cHRM of the Rec.709 primaries and D65. Needs an image with 3 channels; throws atmo::Error.
void WritePng(const std::filesystem::path& path, const Image& image, const ToneMapping& mapping);

// Radiance HDR (RGBE, Ward 1991; the format of Radiance's `ra_rgbe` and of three.js's HDRLoader):
// the header "#?RADIANCE", "FORMAT=32-bit_rle_rgbe", the resolution line "-Y H +X W" (rows from the
// top), then each pixel as 4 bytes, mantissas of R, G, B with a shared exponent, uncompressed
// scanlines (which every RGBE reader takes). Linear values as they are (no exposure); NaN and
// negative values as 0, values above the format's range clamp. Needs 3 channels; atomic.
void WriteRadianceHdr(const std::filesystem::path& path, const Image& image);

// Calls write(temporary_path) and renames the temporary file onto `path`. If `write` throws, the
// temporary file is removed and the error is rethrown as atmo::Error naming `path`. Fails early,
// before calling `write`, when the target's folder does not exist or is not writable, or when
// `path` exists and is not a regular file (a directory, device, FIFO or socket: /dev/null stays
// a device). A symbolic link is written through: its final target is replaced and the link kept;
// a dangling link is refused. A file replaced keeps its mode and owner (refused when the owner
// cannot be kept). The temporary file is fsync'ed before the rename and the folder after it.
void WriteFileAtomically(const std::filesystem::path& path,
                         const std::function<void(const std::filesystem::path&)>& write);
// WriteFileAtomically of a whole text.
void WriteTextFileAtomically(const std::filesystem::path& path, const std::string& text);

// Several files published as one set: Stage writes each into a complete temporary file beside
// its target, with every check of WriteFileAtomically; Commit renames them in the order they were
// staged (put a manifest last: it appears last) and fsyncs their folders. When anything fails
// before Commit, or the set is destroyed without it, no target changes and the temporaries are
// removed (SIGINT/SIGTERM remove them too, include/atmo/interrupt.h). Throws atmo::Error naming
// the file. Readers that must never see a half-published set take a lock as well
// (include/atmo/elek.h does).
class AtomicFileSet {
 public:
  AtomicFileSet();
  ~AtomicFileSet();
  AtomicFileSet(const AtomicFileSet&) = delete;
  AtomicFileSet& operator=(const AtomicFileSet&) = delete;
  void Stage(const std::filesystem::path& path, const std::function<void(const std::filesystem::path&)>& write);
  void Commit();

 private:
  struct Staged;
  std::vector<Staged> staged_;
  bool committed_ = false;
};

// The most bytes ReadFileBounded reads by default: 64 MiB, above every config, grid and manifest
// atmo writes (a 4096-channel config is ~1 MiB) and far below the memory of any machine.
inline constexpr std::uintmax_t kMaxInputFileBytes = std::uintmax_t{64} << 20;

// The whole of a regular file, for text inputs (configs, grids, manifests). Throws atmo::Error
// "cannot read WHAT'PATH': REASON" for a missing file, a directory ("is a directory"), anything
// that is not a regular file (a device such as /dev/zero, a FIFO: opened without blocking), and
// a file of more than `max_bytes`. `what` is e.g. "config " or "" (the message then reads
// "cannot read 'PATH': ...").
std::string ReadFileBounded(const std::filesystem::path& path, const std::string& what = "",
                            std::uintmax_t max_bytes = kMaxInputFileBytes);

}  // namespace atmo
