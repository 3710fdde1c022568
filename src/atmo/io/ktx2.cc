// A minimal KTX 2.0 writer for uncompressed RGBA float cubemaps (atmo/cubemap.h), following the
// Khronos KTX File Format Specification 2.0 and the Khronos Data Format Specification 1.3.
//
// File layout (all little endian):
//   identifier      12 bytes  «KTX 20»\r\n\x1A\n
//   header          9 x UInt32: vkFormat, typeSize, pixelWidth, pixelHeight, pixelDepth (0),
//                   layerCount (0), faceCount (6), levelCount, supercompressionScheme (0)
//   index           dfdByteOffset, dfdByteLength, kvdByteOffset, kvdByteLength (UInt32),
//                   sgdByteOffset, sgdByteLength (UInt64, 0: no supercompression global data)
//   level index     levelCount x {byteOffset, byteLength, uncompressedByteLength} (UInt64),
//                   entry 0 the base level
//   DFD             dfdTotalSize, then one basic descriptor block with 4 samples (R, G, B, A)
//   KVD             {keyAndValueByteLength, key NUL value NUL, padding to 4 bytes}, sorted by key
//   level data      from the smallest level to the base level (the specification's order, so
//                   that a stream shows a small level first), each aligned to
//                   lcm(texel block size, 4) bytes; within a level the faces +X, -X, +Y, -Y, +Z,
//                   -Z, each rows from t = 0 (KTXorientation "rd": s right, t down).
#include <bit>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <fstream>
#include <stdexcept>
#include <string>
#include <vector>

#include "atmo/cubemap.h"
#include "atmo/error.h"

namespace atmo {
namespace {

constexpr std::uint32_t kVkFormatR16G16B16A16Sfloat = 97;
constexpr std::uint32_t kVkFormatR32G32B32A32Sfloat = 109;

class Bytes {
 public:
  void U32(std::uint32_t v) {
    for (int i = 0; i < 4; ++i) data_.push_back(static_cast<std::uint8_t>(v >> (8 * i)));
  }
  void U64(std::uint64_t v) {
    for (int i = 0; i < 8; ++i) data_.push_back(static_cast<std::uint8_t>(v >> (8 * i)));
  }
  void U16(std::uint16_t v) {
    data_.push_back(static_cast<std::uint8_t>(v));
    data_.push_back(static_cast<std::uint8_t>(v >> 8));
  }
  void Raw(const void* p, std::size_t n) {
    const auto* b = static_cast<const std::uint8_t*>(p);
    data_.insert(data_.end(), b, b + n);
  }
  void PadTo(std::size_t alignment) {
    while (data_.size() % alignment != 0) data_.push_back(0);
  }
  void PatchU64(std::size_t at, std::uint64_t v) {
    for (int i = 0; i < 8; ++i) data_[at + i] = static_cast<std::uint8_t>(v >> (8 * i));
  }
  void PatchU32(std::size_t at, std::uint32_t v) {
    for (int i = 0; i < 4; ++i) data_[at + i] = static_cast<std::uint8_t>(v >> (8 * i));
  }
  std::size_t size() const { return data_.size(); }
  const std::vector<std::uint8_t>& data() const { return data_; }

 private:
  std::vector<std::uint8_t> data_;
};

}  // namespace

std::uint16_t FloatToHalf(float value) {
  const std::uint32_t f = std::bit_cast<std::uint32_t>(value);
  const std::uint32_t sign = (f >> 16) & 0x8000u;
  const std::uint32_t magnitude = f & 0x7fffffffu;
  if (magnitude > 0x7f800000u) return static_cast<std::uint16_t>(sign | 0x7e00u);  // NaN
  // 65504 is the largest half; above it (with +inf) clamp rather than overflow.
  if (magnitude >= 0x477fe000u) return static_cast<std::uint16_t>(sign | 0x7bffu);
  if (magnitude < 0x38800000u) {
    // Below the smallest normal half (2^-14): a subnormal half, m x 2^-24, rounded to nearest even
    // (the float's mantissa with its implicit bit, shifted).
    if (magnitude < 0x33000000u) return static_cast<std::uint16_t>(sign);  // < 2^-25: rounds to 0
    const int exponent = static_cast<int>(magnitude >> 23);               // biased, 102..112
    const std::uint32_t mantissa = (magnitude & 0x7fffffu) | 0x800000u;
    const int shift = 126 - exponent;  // 14..24: the value is mantissa x 2^(exponent - 150)
    std::uint32_t half = mantissa >> shift;
    const std::uint32_t rest = mantissa & ((1u << shift) - 1u);
    const std::uint32_t halfway = 1u << (shift - 1);
    if (rest > halfway || (rest == halfway && (half & 1u))) ++half;
    return static_cast<std::uint16_t>(sign | half);
  }
  // Normal: rebias the exponent (127 -> 15) and round the 23-bit mantissa to 10 bits, to nearest
  // even; a carry out of the mantissa correctly increments the exponent.
  std::uint32_t half = ((magnitude - 0x38000000u) >> 13);
  const std::uint32_t rest = magnitude & 0x1fffu;
  if (rest > 0x1000u || (rest == 0x1000u && (half & 1u))) ++half;
  return static_cast<std::uint16_t>(sign | half);
}

float HalfToFloat(std::uint16_t h) {
  const std::uint32_t sign = static_cast<std::uint32_t>(h & 0x8000u) << 16;
  const std::uint32_t exponent = (h >> 10) & 0x1fu;
  const std::uint32_t mantissa = h & 0x3ffu;
  if (exponent == 0) {
    const float v = std::ldexp(static_cast<float>(mantissa), -24);
    return sign ? -v : v;
  }
  if (exponent == 31) return std::bit_cast<float>(sign | 0x7f800000u | (mantissa << 13));
  return std::bit_cast<float>(sign | ((exponent + 112u) << 23) | (mantissa << 13));
}

std::vector<std::uint8_t> EncodeKtx2(std::span<const Cubemap> levels, bool float32, const std::string& writer) {
  const auto fail = [&](const std::string& reason) { throw Error(reason); };
  if (levels.empty()) fail("a KTX2 cubemap needs at least one level");
  const int base = levels[0].face_size;
  for (std::size_t l = 0; l < levels.size(); ++l) {
    const int expected = std::max(1, base >> l);
    if (levels[l].face_size != expected) {
      fail("level " + std::to_string(l) + " is " + std::to_string(levels[l].face_size) + " texels wide, not " +
           std::to_string(expected));
    }
    if (levels[l].channels() != 3) fail("KTX2 levels need 3 channels (RGB), level " + std::to_string(l) + " has " +
                                        std::to_string(levels[l].channels()));
    for (const Image& face : levels[l].faces) {
      if (face.width != expected || face.height != expected) fail("a face does not match its level's size");
    }
  }
  if (base >= 1 && levels.size() > static_cast<std::size_t>(std::bit_width(static_cast<unsigned>(base)))) {
    fail("more levels than a " + std::to_string(base) + "-texel base has");
  }

  const std::uint32_t type_size = float32 ? 4 : 2;
  const std::uint32_t texel_bytes = 4 * type_size;
  const std::uint32_t level_count = static_cast<std::uint32_t>(levels.size());
  Bytes out;
  const std::uint8_t identifier[12] = {0xAB, 0x4B, 0x54, 0x58, 0x20, 0x32, 0x30, 0xBB, 0x0D, 0x0A, 0x1A, 0x0A};
  out.Raw(identifier, sizeof(identifier));
  out.U32(float32 ? kVkFormatR32G32B32A32Sfloat : kVkFormatR16G16B16A16Sfloat);
  out.U32(type_size);
  out.U32(static_cast<std::uint32_t>(base));  // pixelWidth
  out.U32(static_cast<std::uint32_t>(base));  // pixelHeight
  out.U32(0);                                 // pixelDepth: not 3D
  out.U32(0);                                 // layerCount: not an array
  out.U32(kCubeFaceCount);                    // faceCount
  out.U32(level_count);
  out.U32(0);  // supercompressionScheme: none
  const std::size_t index_at = out.size();
  for (int i = 0; i < 4; ++i) out.U32(0);  // dfd/kvd offsets and lengths, patched below
  out.U64(0);                              // sgdByteOffset
  out.U64(0);                              // sgdByteLength
  const std::size_t level_index_at = out.size();
  for (std::uint32_t l = 0; l < level_count; ++l) {
    out.U64(0);
    out.U64(0);
    out.U64(0);
  }

  // Data format descriptor: one basic block (Khronos Data Format 1.3, section 5), 24 bytes of
  // header and 16 bytes per sample.
  const std::size_t dfd_at = out.size();
  const std::uint32_t block_size = 24 + 16 * 4;
  out.U32(4 + block_size);                        // dfdTotalSize
  out.U32(0);                                     // vendorId KHRONOS (0) | descriptorType BASICFORMAT (0) << 17
  out.U32(2u | (block_size << 16));               // versionNumber 2 (1.3) | descriptorBlockSize
  const std::uint32_t primaries = levels[0].faces[0].colour_space == ColourSpace::kLinearSrgb ? 1u : 0u;  // BT709
  out.U32(1u | (primaries << 8) | (1u << 16));    // model RGBSDA | primaries | transfer LINEAR | flags: straight alpha
  out.U32(0);                                     // texelBlockDimension0..3: 1 x 1 x 1 x 1 (stored minus 1)
  out.U32(texel_bytes);                           // bytesPlane0
  out.U32(0);                                     // bytesPlane4..7
  const std::uint32_t channel_ids[4] = {0, 1, 2, 15};  // KHR_DF_CHANNEL_RGBSDA_R, G, B, ALPHA
  const std::uint32_t bits = 8 * type_size;
  for (int c = 0; c < 4; ++c) {
    // Qualifiers FLOAT (0x80) and SIGNED (0x40): an SFLOAT channel; its lower and upper are the
    // 32-bit floats -1 and 1 (the data format specification's convention for float samples).
    const std::uint32_t channel_type = channel_ids[c] | 0x80u | 0x40u;
    out.U32(static_cast<std::uint32_t>(c) * bits | ((bits - 1) << 16) | (channel_type << 24));
    out.U32(0);            // samplePosition0..3
    out.U32(0xBF800000u);  // sampleLower: -1.0f
    out.U32(0x3F800000u);  // sampleUpper: 1.0f
  }
  const std::size_t dfd_length = out.size() - dfd_at;

  // Key/value data, sorted by key (byte order): KTXorientation before KTXwriter.
  const std::size_t kvd_at = out.size();
  const auto key_value = [&](const std::string& key, const std::string& value) {
    out.U32(static_cast<std::uint32_t>(key.size() + 1 + value.size() + 1));
    out.Raw(key.c_str(), key.size() + 1);
    out.Raw(value.c_str(), value.size() + 1);
    out.PadTo(4);
  };
  key_value("KTXorientation", "rd");
  key_value("KTXwriter", writer);
  const std::size_t kvd_length = out.size() - kvd_at;
  out.PatchU32(index_at, static_cast<std::uint32_t>(dfd_at));
  out.PatchU32(index_at + 4, static_cast<std::uint32_t>(dfd_length));
  out.PatchU32(index_at + 8, static_cast<std::uint32_t>(kvd_at));
  out.PatchU32(index_at + 12, static_cast<std::uint32_t>(kvd_length));

  // Levels, smallest first; the alignment is lcm(texel block size, 4) = the texel size (8 or 16).
  for (std::uint32_t l = level_count; l-- > 0;) {
    out.PadTo(texel_bytes);
    const std::size_t at = out.size();
    for (const Image& face : levels[l].faces) {
      for (std::size_t p = 0; p < static_cast<std::size_t>(face.width) * face.height; ++p) {
        for (int c = 0; c < 4; ++c) {
          const float v = c < 3 ? face.pixels[3 * p + c] : 1.0f;
          if (float32) {
            out.U32(std::bit_cast<std::uint32_t>(v));
          } else {
            out.U16(FloatToHalf(v));
          }
        }
      }
    }
    const std::uint64_t length = out.size() - at;
    out.PatchU64(level_index_at + 24 * l, at);
    out.PatchU64(level_index_at + 24 * l + 8, length);
    out.PatchU64(level_index_at + 24 * l + 16, length);
  }

  return out.data();
}

void WriteKtx2(const std::filesystem::path& path, std::span<const Cubemap> levels, bool float32,
               const std::string& writer) {
  std::vector<std::uint8_t> bytes;
  try {
    bytes = EncodeKtx2(levels, float32, writer);
  } catch (const Error& error) {
    throw Error("cannot write '" + path.string() + "': " + error.what());
  }
  WriteFileAtomically(path, [&](const std::filesystem::path& temporary) {
    std::ofstream stream(temporary, std::ios::binary | std::ios::trunc);
    if (!stream) throw std::runtime_error("cannot create '" + temporary.string() + "'");
    stream.write(reinterpret_cast<const char*>(bytes.data()), static_cast<std::streamsize>(bytes.size()));
    stream.close();
    if (!stream) throw std::runtime_error("error while writing '" + temporary.string() + "'");
  });
}

}  // namespace atmo
