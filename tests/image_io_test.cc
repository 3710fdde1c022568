// Tests of include/atmo/image.h: EXR round trips, PNG encoding, tone mapping, atomic writes.
#include <png.h>

#include <algorithm>
#include <array>
#include <atomic>
#include <cmath>
#include <csetjmp>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <limits>
#include <random>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include <ImfDoubleAttribute.h>
#include <ImfHeader.h>
#include <ImfInputFile.h>
#include <ImfStringAttribute.h>
#include <gtest/gtest.h>
#include <unistd.h>

#include "atmo/error.h"
#include "atmo/image.h"

namespace atmo {
namespace {

namespace fs = std::filesystem;

// A fresh, empty directory per test, removed with everything in it afterwards.
class TempDir {
 public:
  TempDir() {
    static std::atomic<int> counter{0};
    const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
    std::string name = "atmo_image_io_";
    if (info != nullptr) name += std::string(info->test_suite_name()) + "_" + info->name() + "_";
    name += std::to_string(::getpid()) + "_" + std::to_string(counter++);
    path_ = fs::temp_directory_path() / name;
    fs::remove_all(path_);
    fs::create_directories(path_);
  }
  ~TempDir() {
    std::error_code ignored;
    fs::remove_all(path_, ignored);
  }
  const fs::path& path() const { return path_; }
  fs::path operator/(const std::string& name) const { return path_ / name; }
  std::vector<std::string> Entries() const {
    std::vector<std::string> names;
    for (const auto& entry : fs::directory_iterator(path_)) names.push_back(entry.path().filename().string());
    std::sort(names.begin(), names.end());
    return names;
  }

 private:
  fs::path path_;
};

std::string ReadBytes(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  return std::string(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
}

void WriteBytes(const fs::path& path, const std::string& bytes) {
  std::ofstream out(path, std::ios::binary);
  out << bytes;
}

// An image whose values cover the float range: zero, denormals, tiny, huge, negative, and
// arbitrary bit patterns of finite floats.
Image MakeTestImage(int width, int height, int channels, unsigned seed) {
  Image image(width, height, channels);
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> uniform(-10.0f, 10.0f);
  const float specials[] = {0.0f, -0.0f, std::numeric_limits<float>::denorm_min(), std::numeric_limits<float>::min(),
                            1e-30f, std::numeric_limits<float>::max(), -3.0e38f, 1.0f / 3.0f};
  for (std::size_t i = 0; i < image.pixels.size(); ++i) {
    image.pixels[i] = i < std::size(specials) ? specials[i] : uniform(rng) * std::pow(10.0f, uniform(rng));
  }
  return image;
}

void ExpectBitExact(const std::vector<float>& expected, const std::vector<float>& actual) {
  ASSERT_EQ(expected.size(), actual.size());
  for (std::size_t i = 0; i < expected.size(); ++i) {
    std::uint32_t a = 0, b = 0;
    std::memcpy(&a, &expected[i], sizeof a);
    std::memcpy(&b, &actual[i], sizeof b);
    ASSERT_EQ(a, b) << "value " << i << ": " << expected[i] << " vs " << actual[i];
  }
}

// A PNG as stored: samples without any transformation (no gamma or colour conversion, 16-bit
// samples as read), and its colour chunks. Read with libpng's full API, not the writer's code.
struct RawPng {
  int width = 0, height = 0, channels = 0, bit_depth = 0;
  std::vector<int> samples;  // interleaved, row 0 first
  bool srgb = false;         // an sRGB chunk
  double gamma = 0.0;        // the gAMA chunk's value, 0 without one
  bool chrm = false;         // a cHRM chunk, with:
  double white_x = 0, white_y = 0, red_x = 0, red_y = 0, green_x = 0, green_y = 0, blue_x = 0, blue_y = 0;
};

RawPng ReadPngRaw(const fs::path& path) {
  std::FILE* file = std::fopen(path.c_str(), "rb");
  if (file == nullptr) throw std::runtime_error("cannot open " + path.string());
  png_structp png = png_create_read_struct(PNG_LIBPNG_VER_STRING, nullptr, nullptr, nullptr);
  png_infop info = png_create_info_struct(png);
  RawPng raw;
  if (setjmp(png_jmpbuf(png))) {
    png_destroy_read_struct(&png, &info, nullptr);
    std::fclose(file);
    throw std::runtime_error("libpng cannot read " + path.string());
  }
  png_init_io(png, file);
  png_read_png(png, info, PNG_TRANSFORM_IDENTITY, nullptr);
  raw.width = static_cast<int>(png_get_image_width(png, info));
  raw.height = static_cast<int>(png_get_image_height(png, info));
  raw.channels = png_get_channels(png, info);
  raw.bit_depth = png_get_bit_depth(png, info);
  int intent = 0;
  raw.srgb = png_get_sRGB(png, info, &intent) != 0;
  if (!png_get_gAMA(png, info, &raw.gamma)) raw.gamma = 0.0;
  raw.chrm = png_get_cHRM(png, info, &raw.white_x, &raw.white_y, &raw.red_x, &raw.red_y, &raw.green_x, &raw.green_y,
                          &raw.blue_x, &raw.blue_y) != 0;
  png_bytepp rows = png_get_rows(png, info);
  const int bytes_per_sample = raw.bit_depth / 8;
  raw.samples.reserve(static_cast<std::size_t>(raw.width) * raw.height * raw.channels);
  for (int y = 0; y < raw.height; ++y) {
    for (int i = 0; i < raw.width * raw.channels; ++i) {
      const png_byte* at = rows[y] + i * bytes_per_sample;
      raw.samples.push_back(bytes_per_sample == 2 ? (at[0] << 8) | at[1] : at[0]);  // big-endian
    }
  }
  png_destroy_read_struct(&png, &info, nullptr);
  std::fclose(file);
  return raw;
}

// The 8-bit samples of an RGB (rgba false) or RGBA PNG, as stored.
std::vector<png_byte> DecodePng(const fs::path& path, bool rgba, int* width, int* height) {
  const RawPng raw = ReadPngRaw(path);
  if (raw.bit_depth != 8 || raw.channels != (rgba ? 4 : 3)) throw std::runtime_error("unexpected PNG layout");
  *width = raw.width;
  *height = raw.height;
  return std::vector<png_byte>(raw.samples.begin(), raw.samples.end());
}

std::uint8_t ExpectedByte(float linear, const ToneMapping& mapping) {
  return static_cast<std::uint8_t>(std::lround(255.0 * static_cast<double>(ToneMapValue(linear, mapping))));
}

// ------------------------------------------------------------------------------------------------
// EXR

TEST(Exr, RoundTripIsBitExactWithMetadata) {
  TempDir dir;
  const Image image = MakeTestImage(37, 23, 3, 1);
  const ImageMetadata metadata = {{"atmo:model", "hillaire"}, {"atmo:parameters", "{\"preset\": \"earth\"}"},
                                  {"atmo:exposure", "10"}, {"comment", ""}};
  WriteExr(dir / "sky.exr", image, metadata);

  ImageMetadata read_metadata;
  const Image read = ReadExr(dir / "sky.exr", &read_metadata);
  EXPECT_EQ(read.width, 37);
  EXPECT_EQ(read.height, 23);
  EXPECT_EQ(read.channels, 3);
  EXPECT_TRUE(read.alpha.empty());
  ExpectBitExact(image.pixels, read.pixels);

  // ReadExr returns the string attributes sorted by name.
  ImageMetadata sorted = metadata;
  std::sort(sorted.begin(), sorted.end());
  EXPECT_EQ(read_metadata, sorted);
}

TEST(Exr, ReadWithoutMetadataPointer) {
  TempDir dir;
  const Image image = MakeTestImage(4, 5, 3, 2);
  WriteExr(dir / "a.exr", image);
  ExpectBitExact(image.pixels, ReadExr(dir / "a.exr").pixels);
}

TEST(Exr, AlphaRoundTrips) {
  TempDir dir;
  Image image = MakeTestImage(16, 9, 3, 3);
  image.alpha.resize(16 * 9);
  for (std::size_t i = 0; i < image.alpha.size(); ++i) image.alpha[i] = static_cast<float>(i % 7) / 6.0f;
  WriteExr(dir / "alpha.exr", image);
  const Image read = ReadExr(dir / "alpha.exr");
  EXPECT_EQ(read.channels, 3);
  ExpectBitExact(image.pixels, read.pixels);
  ExpectBitExact(image.alpha, read.alpha);
}

TEST(Exr, OneChannelImageRoundTrips) {
  TempDir dir;
  const Image image = MakeTestImage(13, 7, 1, 4);
  WriteExr(dir / "one.exr", image, {{"k", "v"}});
  ImageMetadata metadata;
  const Image read = ReadExr(dir / "one.exr", &metadata);
  EXPECT_EQ(read.channels, 1);
  EXPECT_EQ(read.width, 13);
  EXPECT_EQ(read.height, 7);
  ExpectBitExact(image.pixels, read.pixels);
  EXPECT_EQ(metadata, (ImageMetadata{{"k", "v"}}));
}

TEST(Exr, FiveChannelImageRoundTrips) {
  TempDir dir;
  const Image image = MakeTestImage(11, 6, 5, 5);
  WriteExr(dir / "five.exr", image);
  const Image read = ReadExr(dir / "five.exr");
  EXPECT_EQ(read.channels, 5);
  ExpectBitExact(image.pixels, read.pixels);
}

TEST(Exr, TwelveChannelsKeepTheirOrder) {
  // EXR sorts channel names (C0, C1, C10, C11, C2, ...); the reader must map them by index.
  TempDir dir;
  const Image image = MakeTestImage(3, 2, 12, 6);
  WriteExr(dir / "twelve.exr", image);
  const Image read = ReadExr(dir / "twelve.exr");
  EXPECT_EQ(read.channels, 12);
  ExpectBitExact(image.pixels, read.pixels);
}

TEST(RadianceHdr, HeaderAndRgbePixels) {
  TempDir dir;
  Image image(3, 2, 3);
  const float values[6][3] = {{1.0f, 0.5f, 0.25f}, {0.0f, 0.0f, 0.0f}, {3000.0f, 1500.0f, 10.0f},
                              {-1.0f, std::numeric_limits<float>::quiet_NaN(), 2.0f}, {1e-40f, 0.0f, 0.0f},
                              {0.7f, 0.7f, 0.7f}};
  for (int i = 0; i < 6; ++i) {
    for (int c = 0; c < 3; ++c) image.pixels[3 * i + c] = values[i][c];
  }
  WriteRadianceHdr(dir / "sky.hdr", image);
  std::ifstream file(dir / "sky.hdr", std::ios::binary);
  const std::string bytes((std::istreambuf_iterator<char>(file)), std::istreambuf_iterator<char>());
  const std::string header = "#?RADIANCE\n# atmo " ATMO_VERSION "\nFORMAT=32-bit_rle_rgbe\n\n-Y 2 +X 3\n";
  ASSERT_EQ(bytes.substr(0, header.size()), header);
  ASSERT_EQ(bytes.size(), header.size() + 6 * 4);
  const auto pixel = [&](int i) {
    const unsigned char* p = reinterpret_cast<const unsigned char*>(bytes.data()) + header.size() + 4 * i;
    return std::array<int, 4>{p[0], p[1], p[2], p[3]};
  };
  // 1 = 0.5 2^1: mantissas 128, 64, 32 and exponent 1 + 128.
  EXPECT_EQ(pixel(0), (std::array<int, 4>{128, 64, 32, 129}));
  EXPECT_EQ(pixel(1), (std::array<int, 4>{0, 0, 0, 0}));
  EXPECT_EQ(pixel(3), (std::array<int, 4>{0, 0, 128, 130})) << "negative and NaN as 0";
  EXPECT_EQ(pixel(4), (std::array<int, 4>{0, 0, 0, 0})) << "below the format's range";
  // Decoded as (byte + 0.5) 2^(e - 136), every channel within half a mantissa step of its value.
  for (int i : {0, 2, 5}) {
    const auto p = pixel(i);
    for (int c = 0; c < 3; ++c) {
      const double decoded = (p[c] + 0.5) * std::ldexp(1.0, p[3] - 136);
      EXPECT_NEAR(decoded, values[i][c], std::ldexp(1.0, p[3] - 136)) << i << " " << c;
    }
  }
  EXPECT_THROW(WriteRadianceHdr(dir / "one.hdr", Image(2, 2, 1)), Error);
  EXPECT_FALSE(fs::exists(dir / "one.hdr"));
}

TEST(Exr, NumbersInTheMetadataAreTypedAttributes) {
  // A number is a double attribute in the file (OpenEXR's own reader sees the type), text stays
  // text, and ReadExr gives back the text that was written.
  TempDir dir;
  const ImageMetadata metadata = {{"atmo:sunAzimuthDeg", "48.34467976"}, {"atmo:samplesPerPixel", "1099511627776"},
                                  {"atmo:tiny", "-1e-05"},                {"atmo:parameterHash", "0123456789012345"},
                                  {"atmo:wavelengthsNm", "680, 550, 440"}, {"atmo:version", "0.1.0"},
                                  {"atmo:infinite", "inf"},               {"atmo:text", "12 apples"}};
  WriteExr(dir / "typed.exr", MakeTestImage(2, 2, 3, 1), metadata);
  Imf::InputFile file((dir / "typed.exr").c_str());
  const Imf::Header& header = file.header();
  EXPECT_DOUBLE_EQ(header.typedAttribute<Imf::DoubleAttribute>("atmo:sunAzimuthDeg").value(), 48.34467976);
  EXPECT_EQ(header.typedAttribute<Imf::DoubleAttribute>("atmo:samplesPerPixel").value(), 1099511627776.0);
  EXPECT_EQ(header.typedAttribute<Imf::DoubleAttribute>("atmo:tiny").value(), -1e-05);
  for (const char* text : {"atmo:parameterHash", "atmo:wavelengthsNm", "atmo:version", "atmo:infinite", "atmo:text"}) {
    EXPECT_NE(header.findTypedAttribute<Imf::StringAttribute>(text), nullptr) << text;
  }
  ImageMetadata read;
  ReadExr(dir / "typed.exr", &read);
  for (const auto& written : metadata) {
    const auto found =
        std::find_if(read.begin(), read.end(), [&](const auto& entry) { return entry.first == written.first; });
    ASSERT_NE(found, read.end()) << written.first;
    EXPECT_EQ(found->second, written.second) << written.first;
  }
}

TEST(Exr, NamedChannelsRoundTripInReadOrder) {
  // Extra channels "layer.P" (OpenEXR's layers) come after R, G, B, grouped by layer in the order
  // of P, whatever order the image had (EXR itself stores channels sorted by name); the rest
  // follow by name.
  TempDir dir;
  Image image = MakeTestImage(5, 4, 7, 8);
  image.channel_names = {"R", "G", "B", "stderr.B", "stderr.R", "stderr.G", "Z"};
  image.alpha.assign(5 * 4, 0.5f);
  WriteExr(dir / "named.exr", image);
  const Image read = ReadExr(dir / "named.exr");
  ASSERT_EQ(read.channels, 7);
  EXPECT_EQ(read.channel_names,
            (std::vector<std::string>{"R", "G", "B", "stderr.R", "stderr.G", "stderr.B", "Z"}));
  for (const std::string& name : image.channel_names) {
    const int from = image.ChannelIndex(name);
    const int to = read.ChannelIndex(name);
    ASSERT_GE(to, 0) << name;
    for (int y = 0; y < 4; ++y) {
      for (int x = 0; x < 5; ++x) EXPECT_EQ(read.at(x, y, to), image.at(x, y, from)) << name;
    }
  }
  ExpectBitExact(image.alpha, read.alpha);
  // Default names: ChannelIndex knows them too, and ReadExr reports them.
  EXPECT_EQ(Image(1, 1, 3).ChannelIndex("B"), 2);
  EXPECT_EQ(Image(1, 1, 2).ChannelIndex("C1"), 1);
  EXPECT_EQ(Image(1, 1, 3).ChannelIndex("stderr.R"), -1);
  WriteExr(dir / "plain.exr", MakeTestImage(2, 2, 3, 9));
  EXPECT_EQ(ReadExr(dir / "plain.exr").channel_names, (std::vector<std::string>{"R", "G", "B"}));
}

TEST(Exr, BadChannelNamesThrow) {
  TempDir dir;
  Image image(2, 2, 3);
  image.channel_names = {"R", "G"};
  EXPECT_THROW(WriteExr(dir / "n.exr", image), Error);
  image.channel_names = {"R", "G", "G"};
  EXPECT_THROW(WriteExr(dir / "n.exr", image), Error);
  image.channel_names = {"R", "G", "A"};
  EXPECT_THROW(WriteExr(dir / "n.exr", image), Error);
  image.channel_names = {"R", "", "B"};
  EXPECT_THROW(WriteExr(dir / "n.exr", image), Error);
  EXPECT_TRUE(dir.Entries().empty());
}

TEST(Exr, OverwritesAnExistingFile) {
  TempDir dir;
  WriteBytes(dir / "sky.exr", "old contents");
  const Image image = MakeTestImage(2, 2, 3, 7);
  WriteExr(dir / "sky.exr", image);
  ExpectBitExact(image.pixels, ReadExr(dir / "sky.exr").pixels);
  EXPECT_EQ(dir.Entries(), std::vector<std::string>{"sky.exr"});
}

TEST(Exr, BadImageThrowsAndLeavesExistingFileIntact) {
  TempDir dir;
  const fs::path target = dir / "sky.exr";
  WriteBytes(target, "precious");

  Image wrong_size(4, 4, 3);
  wrong_size.pixels.pop_back();
  EXPECT_THROW(WriteExr(target, wrong_size), Error);

  Image wrong_alpha(4, 4, 3);
  wrong_alpha.alpha.assign(3, 1.0f);
  EXPECT_THROW(WriteExr(target, wrong_alpha), Error);

  EXPECT_THROW(WriteExr(target, Image()), Error);

  EXPECT_EQ(ReadBytes(target), "precious");
  EXPECT_EQ(dir.Entries(), std::vector<std::string>{"sky.exr"});
}

TEST(Exr, BadImageMessageNamesThePath) {
  TempDir dir;
  Image image(4, 4, 3);
  image.pixels.resize(5);
  try {
    WriteExr(dir / "x.exr", image);
    FAIL() << "no exception";
  } catch (const Error& e) {
    const std::string message = e.what();
    EXPECT_NE(message.find("cannot write '" + (dir / "x.exr").string() + "'"), std::string::npos) << message;
    EXPECT_EQ(message.find('\n'), std::string::npos);
  }
}

TEST(Exr, DuplicateMetadataNameThrows) {
  TempDir dir;
  EXPECT_THROW(WriteExr(dir / "d.exr", Image(1, 1, 3), {{"a", "1"}, {"a", "2"}}), Error);
  EXPECT_TRUE(dir.Entries().empty());
}

TEST(Exr, MetadataNamedLikeAStandardAttributeThrows) {
  TempDir dir;
  EXPECT_THROW(WriteExr(dir / "d.exr", Image(1, 1, 3), {{"channels", "x"}}), Error);
  EXPECT_TRUE(dir.Entries().empty());
}

TEST(Exr, ReadingAMissingFileThrowsNamingIt) {
  TempDir dir;
  try {
    ReadExr(dir / "missing.exr");
    FAIL() << "no exception";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("cannot read '" + (dir / "missing.exr").string() + "'"), std::string::npos);
  }
}

TEST(Exr, ReadingAFileThatIsNotExrThrowsAtmoError) {
  TempDir dir;
  WriteBytes(dir / "junk.exr", "this is not an OpenEXR file at all");
  try {
    ReadExr(dir / "junk.exr");
    FAIL() << "no exception";
  } catch (const Error& e) {
    const std::string message = e.what();
    EXPECT_EQ(message.rfind("cannot read '", 0), 0u) << message;
    EXPECT_EQ(message.find('\n'), std::string::npos) << message;
  }
}

TEST(Exr, ReadingATruncatedFileThrowsAtmoError) {
  TempDir dir;
  WriteExr(dir / "full.exr", MakeTestImage(64, 64, 3, 8));
  const std::string bytes = ReadBytes(dir / "full.exr");
  WriteBytes(dir / "cut.exr", bytes.substr(0, bytes.size() / 2));
  EXPECT_THROW(ReadExr(dir / "cut.exr"), Error);
}

// ------------------------------------------------------------------------------------------------
// PNG

TEST(Png, SeedMappingBytesAreRoundedToneMappedValues) {
  // The seed's look (per channel, bare gamma, no dither): every byte is round(255 ToneMapValue).
  TempDir dir;
  const ToneMapping mapping = SeedToneMapping(ToneMapper::kExponential, 2.0, 2.2);
  Image image(17, 5, 3);
  for (std::size_t i = 0; i < image.pixels.size(); ++i) {
    image.pixels[i] = static_cast<float>(i) * 0.013f;
  }
  image.pixels[0] = -1.0f;
  image.pixels[1] = std::numeric_limits<float>::quiet_NaN();
  image.pixels[2] = std::numeric_limits<float>::infinity();
  WritePng(dir / "sky.png", image, mapping);

  int width = 0, height = 0;
  const std::vector<png_byte> bytes = DecodePng(dir / "sky.png", /*rgba=*/false, &width, &height);
  ASSERT_EQ(width, 17);
  ASSERT_EQ(height, 5);
  ASSERT_EQ(bytes.size(), image.pixels.size());
  for (std::size_t i = 0; i < bytes.size(); ++i) {
    ASSERT_EQ(bytes[i], ExpectedByte(image.pixels[i], mapping)) << "value " << i;
  }
  EXPECT_EQ(bytes[0], 0);
  EXPECT_EQ(bytes[1], 0);
  EXPECT_EQ(bytes[2], 255);
}

TEST(Png, RowZeroIsTheTopRow) {
  TempDir dir;
  Image image(2, 2, 3);
  for (int c = 0; c < 3; ++c) image.at(0, 0, c) = 100.0f;  // top left white, the rest black
  WritePng(dir / "top.png", image, {ToneMapper::kNone, 1.0, 1.0});
  int width = 0, height = 0;
  const std::vector<png_byte> bytes = DecodePng(dir / "top.png", false, &width, &height);
  EXPECT_EQ(bytes, (std::vector<png_byte>{255, 255, 255, 0, 0, 0, 0, 0, 0, 0, 0, 0}));
}

TEST(Png, AlphaIsWrittenAsRoundedCoverage) {
  TempDir dir;
  const ToneMapping mapping = SeedToneMapping(ToneMapper::kAces, 1.0, 2.2);
  Image image(8, 3, 3);
  image.alpha.resize(8 * 3);
  for (std::size_t i = 0; i < image.pixels.size(); ++i) image.pixels[i] = static_cast<float>(i) * 0.05f;
  for (std::size_t i = 0; i < image.alpha.size(); ++i) image.alpha[i] = static_cast<float>(i) / 23.0f;
  WritePng(dir / "alpha.png", image, mapping);

  int width = 0, height = 0;
  const std::vector<png_byte> bytes = DecodePng(dir / "alpha.png", /*rgba=*/true, &width, &height);
  ASSERT_EQ(bytes.size(), 8u * 3u * 4u);
  for (std::size_t p = 0; p < image.alpha.size(); ++p) {
    ASSERT_EQ(bytes[p * 4 + 3], std::lround(255.0 * image.alpha[p])) << "pixel " << p;
    // Straight (not premultiplied) colour, except where alpha is 0 and colour is meaningless.
    if (bytes[p * 4 + 3] == 255) {
      for (int c = 0; c < 3; ++c) ASSERT_EQ(bytes[p * 4 + c], ExpectedByte(image.pixels[p * 3 + c], mapping));
    }
  }
}

TEST(Png, AlphaOpaqueKeepsColourExact) {
  TempDir dir;
  const ToneMapping mapping = SeedToneMapping(ToneMapper::kExponential, 10.0, 2.2);
  Image image(5, 5, 3);
  image.alpha.assign(25, 1.0f);
  for (std::size_t i = 0; i < image.pixels.size(); ++i) image.pixels[i] = static_cast<float>(i) * 0.004f;
  WritePng(dir / "opaque.png", image, mapping);
  int width = 0, height = 0;
  const std::vector<png_byte> bytes = DecodePng(dir / "opaque.png", true, &width, &height);
  for (std::size_t p = 0; p < 25; ++p) {
    EXPECT_EQ(bytes[p * 4 + 3], 255);
    for (int c = 0; c < 3; ++c) ASSERT_EQ(bytes[p * 4 + c], ExpectedByte(image.pixels[p * 3 + c], mapping));
  }
}

TEST(Png, NeedsThreeChannels) {
  TempDir dir;
  EXPECT_THROW(WritePng(dir / "one.png", Image(4, 4, 1), ToneMapping{}), Error);
  EXPECT_THROW(WritePng(dir / "four.png", Image(4, 4, 4), ToneMapping{}), Error);
  EXPECT_TRUE(dir.Entries().empty());
}

TEST(Png, BadImageLeavesExistingFileIntact) {
  TempDir dir;
  WriteBytes(dir / "sky.png", "precious");
  Image image(4, 4, 3);
  image.pixels.resize(3);
  EXPECT_THROW(WritePng(dir / "sky.png", image, ToneMapping{}), Error);
  EXPECT_EQ(ReadBytes(dir / "sky.png"), "precious");
  EXPECT_EQ(dir.Entries(), std::vector<std::string>{"sky.png"});
}

// ------------------------------------------------------------------------------------------------
// Tone mapping

TEST(ToneMap, ZeroMapsToZero) {
  for (ToneMapper op : {ToneMapper::kExponential, ToneMapper::kAces, ToneMapper::kNone}) {
    EXPECT_EQ(ToneMapValue(0.0f, {op, 10.0, 2.2}), 0.0f);
  }
}

TEST(ToneMap, NanNegativeAndNegativeInfinityMapToZero) {
  for (ToneMapper op : {ToneMapper::kExponential, ToneMapper::kAces, ToneMapper::kNone}) {
    const ToneMapping m{op, 10.0, 2.2};
    EXPECT_EQ(ToneMapValue(std::numeric_limits<float>::quiet_NaN(), m), 0.0f);
    EXPECT_EQ(ToneMapValue(-1.0f, m), 0.0f);
    EXPECT_EQ(ToneMapValue(-std::numeric_limits<float>::infinity(), m), 0.0f);
  }
}

TEST(ToneMap, IsMonotonicNonDecreasing) {
  for (ToneMapper op : {ToneMapper::kExponential, ToneMapper::kAces, ToneMapper::kNone}) {
    for (const ToneMapping& m : {ToneMapping{op, 3.0}, SeedToneMapping(op, 3.0, 1.0), SeedToneMapping(op, 3.0, 2.2)}) {
      float previous = ToneMapValue(0.0f, m);
      for (int i = 1; i <= 20000; ++i) {
        const float x = 1e-6f * std::pow(1.0015f, static_cast<float>(i));  // 1e-6 .. about 1e7
        const float value = ToneMapValue(x, m);
        ASSERT_GE(value, previous) << "x = " << x;
        ASSERT_GE(value, 0.0f);
        ASSERT_LE(value, 1.0f);
        previous = value;
      }
    }
  }
}

TEST(ToneMap, TendsToOneForLargeInputs) {
  for (ToneMapper op : {ToneMapper::kExponential, ToneMapper::kAces}) {
    const ToneMapping m{op, 1.0, 2.2};
    EXPECT_NEAR(ToneMapValue(100.0f, m), 1.0f, 1e-6f);
    EXPECT_EQ(ToneMapValue(1e30f, m), 1.0f);
    EXPECT_EQ(ToneMapValue(std::numeric_limits<float>::max(), m), 1.0f);
    EXPECT_EQ(ToneMapValue(std::numeric_limits<float>::infinity(), m), 1.0f);
  }
}

TEST(ToneMap, NoneScalesByExposureAndClampsAtOne) {
  const ToneMapping m = SeedToneMapping(ToneMapper::kNone, 2.0, 1.0);
  EXPECT_FLOAT_EQ(ToneMapValue(0.25f, m), 0.5f);
  EXPECT_EQ(ToneMapValue(0.5f, m), 1.0f);
  EXPECT_EQ(ToneMapValue(7.0f, m), 1.0f);
  EXPECT_EQ(ToneMapValue(std::numeric_limits<float>::infinity(), m), 1.0f);
}

TEST(ToneMap, MatchesTheStatedCurves) {
  // Double-precision formulas of the header, rounded to float: a few ulps of float apart.
  const double x = 0.07, exposure = 10.0, v = exposure * x;
  EXPECT_NEAR(ToneMapValue(static_cast<float>(x), SeedToneMapping(ToneMapper::kExponential, exposure, 1.0)),
              1.0 - std::exp(-v), 1e-6);
  EXPECT_NEAR(ToneMapValue(static_cast<float>(x), SeedToneMapping(ToneMapper::kAces, exposure, 1.0)),
              v * (2.51 * v + 0.03) / (v * (2.43 * v + 0.59) + 0.14), 1e-6);
}

TEST(ToneMap, GammaIsAPowerOfTheLinearResult) {
  for (ToneMapper op : {ToneMapper::kExponential, ToneMapper::kAces, ToneMapper::kNone}) {
    for (float x : {0.001f, 0.01f, 0.05f, 0.08f}) {
      const float linear = ToneMapValue(x, SeedToneMapping(op, 10.0, 1.0));
      const float encoded = ToneMapValue(x, SeedToneMapping(op, 10.0, 2.2));
      // Float rounding of the two results: relative 1e-6.
      EXPECT_NEAR(encoded, std::pow(static_cast<double>(linear), 1.0 / 2.2), 1e-6) << "x = " << x;
      EXPECT_GE(encoded, linear);  // values in [0, 1] brighten under 1/gamma
    }
  }
}

TEST(ToneMap, ParseAcceptsTheDocumentedNames) {
  EXPECT_EQ(ParseToneMapper("exp"), ToneMapper::kExponential);
  EXPECT_EQ(ParseToneMapper("exponential"), ToneMapper::kExponential);
  EXPECT_EQ(ParseToneMapper("aces"), ToneMapper::kAces);
  EXPECT_EQ(ParseToneMapper("none"), ToneMapper::kNone);
}

TEST(ToneMap, ParseRejectsOtherNamesWithAHelpfulMessage) {
  for (const char* name : {"", "Exp", "reinhard", "aces "}) {
    try {
      ParseToneMapper(name);
      FAIL() << "accepted '" << name << "'";
    } catch (const Error& e) {
      EXPECT_EQ(std::string(e.what()), "unknown tone mapper '" + std::string(name) + "' (use agx, exp, aces or none)");
    }
  }
}

// ------------------------------------------------------------------------------------------------
// Exposure

// A w x h image whose every pixel is the linear colour (r, g, b).
Image Uniform(int width, int height, float r, float g, float b) {
  Image image(width, height, 3);
  for (int y = 0; y < height; ++y) {
    for (int x = 0; x < width; ++x) {
      image.at(x, y, 0) = r;
      image.at(x, y, 1) = g;
      image.at(x, y, 2) = b;
    }
  }
  return image;
}

// A sky-like image: a bluish gradient whose luminance rises geometrically from `low` at the
// bottom row to `high` at the top (cd/m^2), so its log-average luminance is sqrt(low * high).
Image SkyGradient(int width, int height, double low, double high) {
  Image image(width, height, 3);
  for (int y = 0; y < height; ++y) {
    const double t = 1.0 - (y + 0.5) / height;
    const double luminance = low * std::pow(high / low, t);
    // Chromaticity of a clear-sky blue, scaled to the luminance.
    const double r = 0.55, g = 0.8, b = 1.6, scale = luminance / Luminance(r, g, b);
    for (int x = 0; x < width; ++x) {
      image.at(x, y, 0) = static_cast<float>(r * scale);
      image.at(x, y, 1) = static_cast<float>(g * scale);
      image.at(x, y, 2) = static_cast<float>(b * scale);
    }
  }
  return image;
}

TEST(Exposure, Ev100FollowsTheSaturationBasedConvention) {
  // L_max = 1.2 * 2^EV100 maps to 1: EV100 0 -> 1/1.2; every stop halves the exposure.
  EXPECT_DOUBLE_EQ(ExposureFromEv100(0.0), 1.0 / 1.2);
  EXPECT_NEAR(1.0 / ExposureFromEv100(15.0), 1.2 * 32768.0, 1e-9);  // sunny day: 39321.6 cd/m^2
  for (double ev = -6.0; ev <= 18.0; ev += 0.75) {
    EXPECT_NEAR(ExposureFromEv100(ev + 1.0) / ExposureFromEv100(ev), 0.5, 1e-12) << ev;
    EXPECT_NEAR(Ev100FromExposure(ExposureFromEv100(ev)), ev, 1e-12) << ev;
  }
  EXPECT_TRUE(std::isnan(Ev100FromExposure(0.0)));
  EXPECT_TRUE(std::isnan(Ev100FromExposure(-1.0)));
}

TEST(AutoExposure, UniformImageMetersAtLog2OfEightTimesItsLuminance) {
  // EV100 = log2(L S / K) with S = 100, K = 12.5.
  for (double luminance : {0.01, 1.0, 3.0, 8000.0, 1.6e9}) {
    const float v = static_cast<float>(luminance);
    EXPECT_NEAR(AutoExposureEv100(Uniform(8, 4, v, v, v), Metering::kCamera), std::log2(8.0 * luminance), 1e-6)
        << luminance;
  }
  // Only the luminance counts, not the colour.
  const double y = Luminance(2.0, 1.0, 0.5);
  EXPECT_NEAR(AutoExposureEv100(Uniform(3, 3, 2.0f, 1.0f, 0.5f), Metering::kCamera), std::log2(8.0 * y), 1e-6);
}

TEST(AutoExposure, ScalingTheImageShiftsEv100ByLog2OfTheScale) {
  const Image sky = SkyGradient(16, 64, 1.0, 10.0);
  Image brighter = sky;
  for (float& v : brighter.pixels) v *= 1000.0f;
  EXPECT_NEAR(AutoExposureEv100(brighter, Metering::kCamera) - AutoExposureEv100(sky, Metering::kCamera),
              std::log2(1000.0), 1e-4);
  // The gradient's log-average is sqrt(1 * 10): the percentile clamps move it only slightly.
  EXPECT_NEAR(AutoExposureEv100(sky, Metering::kCamera), std::log2(8.0 * std::sqrt(10.0)), 0.05);
  // Adaptive metering follows the luminance more slowly: 1000 times brighter is less than 10
  // stops more exposure, because the brighter scene is also given a higher key.
  const double adaptive_shift = AutoExposureEv100(brighter) - AutoExposureEv100(sky);
  EXPECT_GT(adaptive_shift, 7.0);
  EXPECT_LT(adaptive_shift, std::log2(1000.0) - 0.5);
}

// The mean display grey level (sRGB-encoded display luminance) of an auto-exposed sky.
double MeanDisplayGrey(const Image& sky, ToneMapping mapping, Metering metering) {
  mapping.exposure = ExposureFromEv100(AutoExposureEv100(sky, metering));
  double sum = 0.0;
  for (int y = 0; y < sky.height; ++y) {
    const auto d = ToneMapPixel(sky.at(0, y, 0), sky.at(0, y, 1), sky.at(0, y, 2), mapping);
    sum += SrgbEncode(Luminance(SrgbDecode(d[0]), SrgbDecode(d[1]), SrgbDecode(d[2])));
  }
  return sum / sky.height;
}

TEST(AutoExposure, CameraMeteringMakesTwilightAndNoonSkiesMidGrey) {
  // The reflected-light meter places a twilight sky (1..10 cd/m^2) and a noon sky
  // (5000..10000 cd/m^2) both in the middle of the display range, neither black nor white.
  for (const ToneMapper op : {ToneMapper::kExponential, ToneMapper::kAgx}) {
    ToneMapping mapping;
    mapping.op = op;
    const double twilight = MeanDisplayGrey(SkyGradient(4, 128, 1.0, 10.0), mapping, Metering::kCamera);
    const double noon = MeanDisplayGrey(SkyGradient(4, 128, 5000.0, 10000.0), mapping, Metering::kCamera);
    EXPECT_GT(twilight, 0.25);
    EXPECT_LT(twilight, 0.6);
    EXPECT_NEAR(noon, twilight, 0.02) << "the camera meter cannot tell noon from twilight";
  }
}

TEST(AutoExposure, AdaptiveMeteringKeepsNoonBrightAndNightDark) {
  // A time-lapse's frames: noon, civil twilight, nautical twilight and night skies.
  const ToneMapping mapping;  // AgX
  const double noon = MeanDisplayGrey(SkyGradient(4, 128, 5000.0, 10000.0), mapping, Metering::kAdaptive);
  const double civil = MeanDisplayGrey(SkyGradient(4, 128, 20.0, 80.0), mapping, Metering::kAdaptive);
  const double nautical = MeanDisplayGrey(SkyGradient(4, 128, 0.5, 2.0), mapping, Metering::kAdaptive);
  const double night = MeanDisplayGrey(SkyGradient(4, 128, 5e-4, 2e-3), mapping, Metering::kAdaptive);
  EXPECT_GT(noon, 0.45) << "noon at or above the display's mid grey";
  EXPECT_LT(noon, 0.65) << "but not washed out";
  EXPECT_GT(noon, civil + 0.03);
  EXPECT_GT(civil, nautical + 0.1);
  EXPECT_GT(nautical, night + 0.05);
  EXPECT_LT(night, 0.25);
  // A clear noon sky gets the sunny-16 exposure (EV100 15 for a sunlit scene).
  EXPECT_NEAR(AutoExposureEv100(Uniform(8, 8, 7000.0f, 7000.0f, 7000.0f)), 15.0, 0.1);
}

TEST(AutoExposure, AdaptationKeyIsKrawczyksAndRisesWithLuminance) {
  // Krawczyk, Myszkowski and Seidel 2005: a = 1.03 - 2 / (2 + log10(L + 1)).
  EXPECT_NEAR(AdaptationKey(0.0), 0.03, 1e-12);
  EXPECT_NEAR(AdaptationKey(9.0), 1.03 - 2.0 / 3.0, 1e-12);
  EXPECT_NEAR(AdaptationKey(99999.0), 1.03 - 2.0 / 7.0, 1e-12);
  double previous = 0.0;
  for (double l = 1e-6; l < 1e9; l *= 3.0) {
    EXPECT_GT(AdaptationKey(l), previous);
    previous = AdaptationKey(l);
  }
  EXPECT_NEAR(MeteringKey(7000.0), 0.18, 1e-12);
  EXPECT_EQ(AdaptationKey(std::numeric_limits<double>::quiet_NaN()), 0.01);
  EXPECT_EQ(AdaptationKey(-1.0), 0.01);
  EXPECT_EQ(ParseMetering("camera"), Metering::kCamera);
  EXPECT_EQ(ParseMetering("adaptive"), Metering::kAdaptive);
  EXPECT_THROW(ParseMetering("spot"), Error);
}

TEST(AutoExposure, ASmallBrightSunDoesNotSetTheExposure) {
  // 1.5% of the pixels at the sun's 1.6e9 cd/m^2 in a 8000 cd/m^2 sky: the plain geometric mean
  // would rise by 0.015 * log2(2e5) = 0.26 stops; clamped to the 98th percentile, not at all.
  const Image sky = Uniform(100, 100, 8000.0f, 8000.0f, 8000.0f);
  Image with_sun = sky;
  for (int y = 0; y < 10; ++y) {
    for (int x = 0; x < 15; ++x) {
      for (int c = 0; c < 3; ++c) with_sun.at(x, y, c) = 1.6e9f;
    }
  }
  EXPECT_NEAR(AutoExposureEv100(with_sun), AutoExposureEv100(sky), 1e-9);
  // A sun that fills a quarter of the frame does count.
  Image close_up = sky;
  for (int y = 0; y < 50; ++y) {
    for (int x = 0; x < 50; ++x) {
      for (int c = 0; c < 3; ++c) close_up.at(x, y, c) = 1.6e9f;
    }
  }
  EXPECT_GT(AutoExposureEv100(close_up), AutoExposureEv100(sky) + 3.0);
}

TEST(AutoExposure, SkipsUncoveredAndUnusablePixels) {
  Image image = Uniform(10, 10, 5.0f, 5.0f, 5.0f);
  image.alpha.assign(100, 1.0f);
  for (int x = 0; x < 10; ++x) {
    for (int c = 0; c < 3; ++c) image.at(x, 0, c) = 1e30f;  // outside the fisheye circle
    image.alpha[x] = 0.0f;
  }
  image.at(0, 1, 0) = std::numeric_limits<float>::quiet_NaN();
  image.at(1, 1, 1) = std::numeric_limits<float>::infinity();
  for (int c = 0; c < 3; ++c) image.at(2, 1, c) = 0.0f;
  for (int c = 0; c < 3; ++c) image.at(3, 1, c) = -4.0f;
  EXPECT_NEAR(AutoExposureEv100(image, Metering::kCamera), std::log2(8.0 * 5.0), 1e-6);
}

TEST(AutoExposure, BlackImageGivesZeroAndFewChannelsThrow) {
  EXPECT_EQ(AutoExposureEv100(Image(4, 4, 3)), 0.0);
  EXPECT_THROW(AutoExposureEv100(Image(4, 4, 1)), Error);
  Image broken(4, 4, 3);
  broken.pixels.pop_back();
  EXPECT_THROW(AutoExposureEv100(broken), Error);
  // Monte Carlo images carry R, G, B first, then their standard errors: those are ignored.
  Image six = Image(2, 2, 6);
  for (int y = 0; y < 2; ++y) {
    for (int x = 0; x < 2; ++x) {
      for (int c = 0; c < 6; ++c) six.at(x, y, c) = c < 3 ? 2.0f : 1e6f;
    }
  }
  EXPECT_NEAR(AutoExposureEv100(six, Metering::kCamera), std::log2(16.0), 1e-6);
}

// ------------------------------------------------------------------------------------------------
// Display: sRGB transfer and tone mapping on luminance

TEST(Srgb, MatchesKnownValues) {
  EXPECT_EQ(SrgbEncode(0.0), 0.0);
  EXPECT_EQ(SrgbEncode(1.0), 1.0);
  EXPECT_NEAR(SrgbEncode(0.5), 0.7354, 5e-5);
  EXPECT_NEAR(SrgbEncode(0.18), 0.4614, 5e-5);  // photographic mid grey
  EXPECT_NEAR(SrgbEncode(0.001), 0.01292, 1e-12);  // on the linear toe
  // The two pieces meet at 0.0031308 (to the standard's 4 digits: within 1e-7), and the curve is
  // increasing across the joint.
  const double joint = 0.0031308;
  EXPECT_NEAR(12.92 * joint, 1.055 * std::pow(joint, 1.0 / 2.4) - 0.055, 1e-7);
  EXPECT_NEAR(SrgbEncode(std::nextafter(joint, 0.0)), SrgbEncode(std::nextafter(joint, 1.0)), 1e-7);
  EXPECT_LT(SrgbEncode(joint - 1e-6), SrgbEncode(joint + 1e-6));
  // Out of range clamps; NaN is 0.
  EXPECT_EQ(SrgbEncode(-1.0), 0.0);
  EXPECT_EQ(SrgbEncode(7.0), 1.0);
  EXPECT_EQ(SrgbEncode(std::numeric_limits<double>::quiet_NaN()), 0.0);
  // The inverse.
  for (double x = 0.0; x <= 1.0; x += 1.0 / 1024.0) EXPECT_NEAR(SrgbDecode(SrgbEncode(x)), x, 1e-12) << x;
  EXPECT_NEAR(SrgbDecode(0.7354), 0.5, 1e-4);
}

TEST(Srgb, IsTheDefaultAndBareGammaIsAvailable) {
  const ToneMapping srgb;  // defaults
  EXPECT_EQ(srgb.transfer, DisplayTransfer::kSrgb);
  EXPECT_DOUBLE_EQ(EncodeDisplay(0.5, srgb), SrgbEncode(0.5));
  ToneMapping gamma;
  gamma.transfer = DisplayTransfer::kGamma;
  gamma.gamma = 2.2;
  EXPECT_DOUBLE_EQ(EncodeDisplay(0.5, gamma), std::pow(0.5, 1.0 / 2.2));
  ToneMapping identity;
  identity.transfer = DisplayTransfer::kIdentity;
  EXPECT_EQ(EncodeDisplay(0.5, identity), 0.5);
  EXPECT_EQ(EncodeDisplay(1.5, identity), 1.0);
  EXPECT_EQ(SeedToneMapping().transfer, DisplayTransfer::kGamma);
  EXPECT_EQ(SeedToneMapping().gamma, 2.2);
  // ToneMapValue ends with the same encoding: the curve of kNone at exposure 1 is the identity.
  EXPECT_FLOAT_EQ(ToneMapValue(0.5f, {ToneMapper::kNone, 1.0}), static_cast<float>(SrgbEncode(0.5)));
}

// Linear value of a display value under the default (sRGB) encoding.
double Linear(float display) { return SrgbDecode(display); }

TEST(ToneMapPixel, SaturatedOrangeStaysOrangeAtEveryExposure) {
  // The sunrise sun of an EXR: 2881 : 439 : 9. Its linear G/R and B/R survive every exposure and
  // curve; per channel, the same pixel turns nearly white.
  const float r = 2881.0f, g = 439.0f, b = 9.0f;
  for (ToneMapper op : {ToneMapper::kExponential, ToneMapper::kAces, ToneMapper::kNone}) {
    for (double exposure = 1e-7; exposure < 1e3; exposure *= 3.0) {
      ToneMapping mapping{op, exposure};
      const auto d = ToneMapPixel(r, g, b, mapping);
      ASSERT_GT(d[0], d[1]) << exposure;
      ASSERT_GT(d[1], d[2]) << exposure;
      ASSERT_GT(d[2], 0.0f) << exposure;
      ASSERT_LE(d[0], 1.0f);
      EXPECT_NEAR(Linear(d[1]) / Linear(d[0]), g / r, 1e-3 * g / r) << exposure;
      EXPECT_NEAR(Linear(d[2]) / Linear(d[0]), b / r, 1e-3 * b / r) << exposure;
    }
  }
  const auto seed = ToneMapPixel(r, g, b, SeedToneMapping(ToneMapper::kExponential, 10.0, 2.2));
  EXPECT_GT(seed[1], 0.99f);  // the seed's look: G saturates too, the hue is lost
}

TEST(ToneMapPixel, OutOfRangeColoursKeepTheirChromaticity) {
  std::mt19937 rng(11);
  std::uniform_real_distribution<float> unit(0.0f, 1.0f);
  for (int i = 0; i < 2000; ++i) {
    const float r = unit(rng), g = unit(rng), b = unit(rng);
    const float scale = std::pow(10.0f, 6.0f * unit(rng) - 2.0f);
    const auto d = ToneMapPixel(r * scale, g * scale, b * scale, {ToneMapper::kAces, 1.0});
    const double largest = std::max({r, g, b});
    const double display_largest = std::max({Linear(d[0]), Linear(d[1]), Linear(d[2])});
    ASSERT_LE(std::max({d[0], d[1], d[2]}), 1.0f);
    for (int c = 0; c < 3; ++c) {
      const double input = c == 0 ? r : (c == 1 ? g : b);
      // Each channel relative to the largest, as in the input (float rounding: 1e-5).
      ASSERT_NEAR(Linear(d[c]) / display_largest, input / largest, 1e-5) << i << " channel " << c;
    }
  }
}

TEST(ToneMapPixel, GreyStaysNeutralAndMatchesToneMapValue) {
  for (ToneMapper op : {ToneMapper::kExponential, ToneMapper::kAces, ToneMapper::kNone}) {
    for (float v : {0.0f, 1e-5f, 0.01f, 0.3f, 1.0f, 50.0f, 1e9f}) {
      const ToneMapping mapping{op, 3.0};
      const auto d = ToneMapPixel(v, v, v, mapping);
      EXPECT_EQ(d[0], d[1]) << v;
      EXPECT_EQ(d[1], d[2]) << v;
      EXPECT_NEAR(d[0], ToneMapValue(v, mapping), 1e-6) << v;  // Y = v: the same curve
    }
  }
}

TEST(ToneMapPixel, EveryChannelIsMonotonicInTheExposure) {
  const std::vector<std::array<float, 3>> colours = {
      {2881.0f, 439.0f, 9.0f}, {1.0f, 1.0f, 1.0f}, {0.0f, 0.0f, 1.0f}, {0.2f, 3.0f, 0.01f}, {5.0f, 0.0f, 4.0f}};
  for (ToneMapper op : {ToneMapper::kExponential, ToneMapper::kAces, ToneMapper::kNone}) {
    for (const auto& rgb : colours) {
      std::array<float, 3> previous = {0.0f, 0.0f, 0.0f};
      for (int i = 0; i <= 400; ++i) {
        const double exposure = 1e-6 * std::pow(10.0, i * 0.025);  // 1e-6 .. 1e4
        const auto d = ToneMapPixel(rgb[0], rgb[1], rgb[2], {op, exposure});
        for (int c = 0; c < 3; ++c) {
          ASSERT_GE(d[c], previous[c]) << "exposure " << exposure << " channel " << c;
          ASSERT_LE(d[c], 1.0f);
        }
        previous = d;
      }
    }
  }
}

TEST(ToneMapPixel, BadValuesAreBlackOrExtreme) {
  const ToneMapping mapping{ToneMapper::kExponential, 10.0};
  const float nan = std::numeric_limits<float>::quiet_NaN(), inf = std::numeric_limits<float>::infinity();
  EXPECT_EQ(ToneMapPixel(nan, nan, nan, mapping), (std::array<float, 3>{0.0f, 0.0f, 0.0f}));
  EXPECT_EQ(ToneMapPixel(-1.0f, -2.0f, -inf, mapping), (std::array<float, 3>{0.0f, 0.0f, 0.0f}));
  EXPECT_EQ(ToneMapPixel(1.0f, 1.0f, 1.0f, {ToneMapper::kExponential, -2.0}), (std::array<float, 3>{0.0f, 0.0f, 0.0f}));
  // +inf in one channel: that channel's primary at full brightness.
  const auto red = ToneMapPixel(inf, 1.0f, nan, mapping);
  EXPECT_EQ(red[0], 1.0f);
  EXPECT_LT(red[1], 1e-30f);  // 1 / the largest float, relative to red
  EXPECT_EQ(red[2], 0.0f);
  EXPECT_EQ(ToneMapPixel(inf, inf, inf, mapping), (std::array<float, 3>{1.0f, 1.0f, 1.0f}));
}

// ------------------------------------------------------------------------------------------------
// AgX

TEST(Agx, SceneGreyIsDisplayMidGreyAndTheRangeIsSixteenAndAHalfStops) {
  const ToneMapping agx{ToneMapper::kAgx, 1.0};
  // 0.18 encodes at x = 20/33, where the sigmoid is 1/2: display 0.5 for a 2.2 display.
  const auto grey = AgxDisplay(0.18, 0.18, 0.18);
  for (double c : grey) EXPECT_NEAR(c, 0.5, 1e-9);
  EXPECT_NEAR(ToneMapValue(0.18f, agx), SrgbEncode(std::pow(0.5, 2.2)), 1e-6);
  // The ends: 2^-12.47 and below is black, 2^4.03 (16.3) and above white.
  EXPECT_LT(AgxDisplay(1e-5, 1e-5, 1e-5)[1], 1e-3);
  EXPECT_GT(AgxDisplay(16.3, 16.3, 16.3)[1], 0.999);
  EXPECT_EQ(ToneMapPixel(0.0f, 0.0f, 0.0f, agx), (std::array<float, 3>{0.0f, 0.0f, 0.0f}));
  // Grey stays grey (each inset row sums to 1) and rises monotonically.
  float previous = -1.0f;
  for (double v = 1e-6; v < 100.0; v *= 1.1) {
    const auto d = ToneMapPixel(static_cast<float>(v), static_cast<float>(v), static_cast<float>(v), agx);
    EXPECT_NEAR(d[0], d[1], 1e-6);
    EXPECT_NEAR(d[2], d[1], 1e-6);
    EXPECT_GE(d[1], previous);
    previous = d[1];
  }
}

TEST(Agx, TablesFollowTheClosedFormCurve) {
  // The closed-form sigmoid (docs/display.md) against the tabulated one inside ToneMapPixel, for
  // grey (where the inset and outset are the identity), through the sRGB encoding: within 1e-6.
  const auto sigmoid = [](double x) {
    const double d = x - 20.0 / 33.0;
    return d <= 0.0 ? 0.5 + 2.0 * d * std::pow(1.0 + 59.507875 * std::pow(-d, 3.0), -1.0 / 3.0)
                    : 0.5 + 2.0 * d * std::pow(1.0 + 69.86278913545539 * std::pow(d, 3.25), -4.0 / 13.0);
  };
  double worst = 0.0;
  for (double stops = -12.4; stops < 4.0; stops += 0.0137) {
    const double x = (stops + 12.473931188332413) / 16.5;
    const double expected = SrgbEncode(std::pow(std::clamp(sigmoid(x), 0.0, 1.0), 2.2));
    const float v = static_cast<float>(std::exp2(stops));
    const auto d = ToneMapPixel(v, v, v, {ToneMapper::kAgx, 1.0});
    worst = std::max(worst, std::abs(d[1] - expected));
  }
  EXPECT_LT(worst, 1e-6);
}

TEST(Agx, BrightColoursRollOffToWhiteAndDimOnesKeepTheirHue) {
  const ToneMapping agx{ToneMapper::kAgx, 1.0};
  // A deep orange (the sun near the horizon, R:G:B = 1 : 0.45 : 0.12) far above the range: white.
  const auto sun = ToneMapPixel(400.0f, 180.0f, 48.0f, agx);
  for (float c : sun) EXPECT_GT(c, 0.97f);
  // The same colour at mid exposure keeps its order of channels (still orange).
  const auto dim = ToneMapPixel(0.2f, 0.09f, 0.024f, agx);
  EXPECT_GT(dim[0], dim[1] + 0.05f);
  EXPECT_GT(dim[1], dim[2] + 0.05f);
  // Displayed luminance never falls as the exposure rises, for saturated colours too.
  for (const auto& rgb : {std::array<float, 3>{1.0f, 0.45f, 0.12f}, std::array<float, 3>{0.05f, 0.2f, 1.0f},
                          std::array<float, 3>{0.0f, 1.0f, 0.0f}}) {
    double previous = -1.0;
    for (double e = 1e-4; e < 1e4; e *= 1.2) {
      const auto d = ToneMapPixel(rgb[0], rgb[1], rgb[2], {ToneMapper::kAgx, e});
      const double y = Luminance(SrgbDecode(d[0]), SrgbDecode(d[1]), SrgbDecode(d[2]));
      EXPECT_GE(y, previous - 1e-6) << e;
      previous = y;
    }
  }
  // NaN and negative channels count as 0; +inf saturates to white through the inset.
  const float nan = std::numeric_limits<float>::quiet_NaN(), inf = std::numeric_limits<float>::infinity();
  EXPECT_EQ(ToneMapPixel(nan, -1.0f, nan, agx), (std::array<float, 3>{0.0f, 0.0f, 0.0f}));
  for (float c : ToneMapPixel(inf, 0.0f, 0.0f, agx)) EXPECT_GT(c, 0.97f);
  EXPECT_EQ(ParseToneMapper("agx"), ToneMapper::kAgx);
}

// ------------------------------------------------------------------------------------------------
// PNG: display encoding, dither, 16 bits, colour chunks

TEST(Png, DefaultMappingIsLuminanceSrgbAndDithered) {
  const ToneMapping mapping;
  EXPECT_FALSE(mapping.per_channel);
  EXPECT_EQ(mapping.transfer, DisplayTransfer::kSrgb);
  EXPECT_TRUE(mapping.dither);
  EXPECT_EQ(mapping.bit_depth, 8);
}

TEST(Png, SunriseOrangeIsOrangeInTheFile) {
  // Read back without the writer's code: the decoded linear G/R is that of the EXR value, to the
  // 8-bit rounding (dither off: half a code of G's 8-bit sRGB code, about 1.2% linear).
  TempDir dir;
  for (double exposure : {1e-3, 0.1, 10.0, 1e4}) {
    ToneMapping mapping{ToneMapper::kExponential, exposure};
    mapping.dither = false;
    WritePng(dir / "sun.png", Uniform(2, 2, 2881.0f, 439.0f, 9.0f), mapping);
    int width = 0, height = 0;
    const std::vector<png_byte> bytes = DecodePng(dir / "sun.png", false, &width, &height);
    ASSERT_GT(bytes[0], bytes[1]) << exposure;
    ASSERT_GT(bytes[1], bytes[2]) << exposure;
    const double ratio = SrgbDecode(bytes[1] / 255.0) / SrgbDecode(bytes[0] / 255.0);
    EXPECT_NEAR(ratio, 439.0 / 2881.0, 0.03 * 439.0 / 2881.0) << exposure;
  }
}

// A w x h grey image whose display value (kNone, exposure 1, bare gamma 1: display = linear)
// rises linearly across x from `first_code` to `last_code` 8-bit codes.
Image CodeGradient(int width, int height, double first_code, double last_code) {
  Image image(width, height, 3);
  for (int y = 0; y < height; ++y) {
    for (int x = 0; x < width; ++x) {
      const double code = first_code + (last_code - first_code) * (x + 0.5) / width;
      for (int c = 0; c < 3; ++c) image.at(x, y, c) = static_cast<float>(code / 255.0);
    }
  }
  return image;
}

struct BandingStats {
  double worst_block_mean_error_codes = 0.0;  // over 32x32 blocks, against the exact values
  double changes_along_x = 0.0;  // share of horizontal neighbours with different codes
};

BandingStats MeasureBanding(const Image& image, const std::vector<png_byte>& bytes) {
  BandingStats stats;
  constexpr int kBlock = 32;
  for (int by = 0; by + kBlock <= image.height; by += kBlock) {
    for (int bx = 0; bx + kBlock <= image.width; bx += kBlock) {
      for (int c = 0; c < 3; ++c) {
        double error = 0.0;
        for (int y = by; y < by + kBlock; ++y) {
          for (int x = bx; x < bx + kBlock; ++x) {
            error += bytes[(static_cast<std::size_t>(y) * image.width + x) * 3 + c] - 255.0 * image.at(x, y, c);
          }
        }
        stats.worst_block_mean_error_codes =
            std::max(stats.worst_block_mean_error_codes, std::abs(error) / (kBlock * kBlock));
      }
    }
  }
  int changes = 0, pairs = 0;
  for (int y = 0; y < image.height; ++y) {
    for (int x = 1; x < image.width; ++x) {
      for (int c = 0; c < 3; ++c) {
        const std::size_t i = (static_cast<std::size_t>(y) * image.width + x) * 3 + c;
        changes += bytes[i] != bytes[i - 3];
        ++pairs;
      }
    }
  }
  stats.changes_along_x = static_cast<double>(changes) / pairs;
  return stats;
}

TEST(Png, DitherRemovesBandsOfASlowGradient) {
  // 256 pixels across 4 codes. Rounded, each code is a band 64 pixels wide (the code changes
  // between 3 of 255 neighbours) and a 32x32 block is off by a quarter of a code. Dithered, the
  // bands dissolve into noise (the code changes between a third of the neighbours) and every
  // block's mean is the exact mean within 0.1 code: TPDF noise leaves a per-pixel error of 0.5
  // code rms, so 1/64 code rms for a block's mean.
  TempDir dir;
  const Image image = CodeGradient(256, 64, 100.0, 104.0);
  ToneMapping mapping{ToneMapper::kNone, 1.0, 1.0};
  mapping.transfer = DisplayTransfer::kGamma;
  int width = 0, height = 0;

  mapping.dither = false;
  WritePng(dir / "banded.png", image, mapping);
  const BandingStats banded = MeasureBanding(image, DecodePng(dir / "banded.png", false, &width, &height));
  EXPECT_GT(banded.worst_block_mean_error_codes, 0.2);
  EXPECT_LT(banded.changes_along_x, 0.02);

  mapping.dither = true;
  WritePng(dir / "dithered.png", image, mapping);
  const std::vector<png_byte> bytes = DecodePng(dir / "dithered.png", false, &width, &height);
  const BandingStats dithered = MeasureBanding(image, bytes);
  EXPECT_LT(dithered.worst_block_mean_error_codes, 0.1);
  EXPECT_GT(dithered.changes_along_x, 0.3);
  // +-1 code at most, around the exact value.
  for (std::size_t i = 0; i < bytes.size(); ++i) {
    ASSERT_LE(std::abs(bytes[i] - 255.0 * image.pixels[i]), 1.5) << i;
  }

  // Deterministic: the same image gives the same file.
  WritePng(dir / "again.png", image, mapping);
  EXPECT_EQ(ReadBytes(dir / "again.png"), ReadBytes(dir / "dithered.png"));
}

TEST(Png, DitherKeepsBlackAndWhiteExact) {
  TempDir dir;
  Image image = Uniform(32, 32, 0.0f, 0.0f, 0.0f);
  for (int y = 16; y < 32; ++y) {
    for (int x = 0; x < 32; ++x) {
      for (int c = 0; c < 3; ++c) image.at(x, y, c) = 1e6f;
    }
  }
  WritePng(dir / "bw.png", image, ToneMapping{});
  int width = 0, height = 0;
  const std::vector<png_byte> bytes = DecodePng(dir / "bw.png", false, &width, &height);
  for (std::size_t i = 0; i < bytes.size(); ++i) ASSERT_EQ(bytes[i], i < bytes.size() / 2 ? 0 : 255) << i;
}

TEST(Png, SixteenBitRoundTripsThroughLibpng) {
  TempDir dir;
  Image image = CodeGradient(64, 3, 0.0, 255.0);
  image.alpha.assign(64 * 3, 1.0f);
  image.alpha[5] = 0.25f;
  ToneMapping mapping{ToneMapper::kNone, 1.0};
  mapping.bit_depth = 16;
  mapping.dither = false;
  WritePng(dir / "deep.png", image, mapping);
  const RawPng raw = ReadPngRaw(dir / "deep.png");
  ASSERT_EQ(raw.bit_depth, 16);
  ASSERT_EQ(raw.channels, 4);
  ASSERT_EQ(raw.width, 64);
  ASSERT_EQ(raw.height, 3);
  for (std::size_t p = 0; p < image.alpha.size(); ++p) {
    for (int c = 0; c < 3; ++c) {
      const long expected = std::lround(65535.0 * SrgbEncode(image.pixels[p * 3 + c]));
      ASSERT_EQ(raw.samples[p * 4 + c], expected) << "pixel " << p << " channel " << c;
    }
    ASSERT_EQ(raw.samples[p * 4 + 3], std::lround(65535.0 * image.alpha[p])) << "pixel " << p;
  }

  // Dithered 16 bits: within a code of the exact values.
  mapping.dither = true;
  WritePng(dir / "deep_dithered.png", image, mapping);
  const RawPng dithered = ReadPngRaw(dir / "deep_dithered.png");
  for (std::size_t p = 0; p < image.alpha.size(); ++p) {
    for (int c = 0; c < 3; ++c) {
      ASSERT_LE(std::abs(dithered.samples[p * 4 + c] - 65535.0 * SrgbEncode(image.pixels[p * 3 + c])), 1.5);
    }
  }
}

TEST(Png, IdentityTransferWritesDisplayValuesAsTheyAreTaggedSrgb) {
  // What a chart (atmo compare --image) needs: display-referred values, clamped and rounded.
  TempDir dir;
  Image image(16, 2, 3);
  for (std::size_t i = 0; i < image.pixels.size(); ++i) image.pixels[i] = static_cast<float>(i % 17) / 15.0f;
  ToneMapping mapping = SeedToneMapping(ToneMapper::kNone, 1.0, 1.0);
  mapping.transfer = DisplayTransfer::kIdentity;
  WritePng(dir / "chart.png", image, mapping);
  const RawPng raw = ReadPngRaw(dir / "chart.png");
  EXPECT_TRUE(raw.srgb);
  ASSERT_EQ(raw.samples.size(), image.pixels.size());
  for (std::size_t i = 0; i < image.pixels.size(); ++i) {
    ASSERT_EQ(raw.samples[i], std::lround(255.0 * std::min(image.pixels[i], 1.0f))) << i;
  }
}

TEST(Png, BadBitDepthThrowsAndWritesNothing) {
  TempDir dir;
  for (int depth : {0, 1, 12, 32}) {
    ToneMapping mapping;
    mapping.bit_depth = depth;
    EXPECT_THROW(WritePng(dir / "x.png", Image(2, 2, 3), mapping), Error) << depth;
  }
  EXPECT_TRUE(dir.Entries().empty());
}

TEST(Png, CarriesItsColourSpace) {
  TempDir dir;
  WritePng(dir / "srgb.png", Image(2, 2, 3), ToneMapping{});
  const RawPng srgb = ReadPngRaw(dir / "srgb.png");
  EXPECT_TRUE(srgb.srgb);
  EXPECT_NEAR(srgb.gamma, 1.0 / 2.2, 1e-4);  // the fallback gAMA of an sRGB file

  WritePng(dir / "gamma.png", Image(2, 2, 3), SeedToneMapping(ToneMapper::kExponential, 10.0, 1.8));
  const RawPng gamma = ReadPngRaw(dir / "gamma.png");
  EXPECT_FALSE(gamma.srgb);
  EXPECT_NEAR(gamma.gamma, 1.0 / 1.8, 1e-4);
  ASSERT_TRUE(gamma.chrm);
  EXPECT_NEAR(gamma.white_x, 0.3127, 1e-4);
  EXPECT_NEAR(gamma.white_y, 0.3290, 1e-4);
  EXPECT_NEAR(gamma.red_x, 0.64, 1e-4);
  EXPECT_NEAR(gamma.green_y, 0.60, 1e-4);
  EXPECT_NEAR(gamma.blue_x, 0.15, 1e-4);
}

// ------------------------------------------------------------------------------------------------
// Atomic writes

TEST(WriteFileAtomically, WritesThroughATemporaryFileInTheSameDirectory) {
  TempDir dir;
  fs::path seen;
  WriteFileAtomically(dir / "out.txt", [&](const fs::path& temporary) {
    seen = temporary;
    EXPECT_EQ(temporary.parent_path(), dir.path());
    EXPECT_NE(temporary.filename(), "out.txt");
    EXPECT_FALSE(fs::exists(dir / "out.txt"));
    WriteBytes(temporary, "hello");
  });
  EXPECT_EQ(ReadBytes(dir / "out.txt"), "hello");
  EXPECT_FALSE(fs::exists(seen));
  EXPECT_EQ(dir.Entries(), std::vector<std::string>{"out.txt"});
}

TEST(WriteFileAtomically, ThrowingWriterLeavesTargetIdenticalAndNoTemporaryFiles) {
  TempDir dir;
  const fs::path target = dir / "sky.exr";
  const std::string original("old\0bytes\xff", 10);
  WriteBytes(target, original);
  try {
    WriteFileAtomically(target, [](const fs::path& temporary) {
      WriteBytes(temporary, "partial");
      throw std::runtime_error("disk on fire");
    });
    FAIL() << "no exception";
  } catch (const Error& e) {
    EXPECT_EQ(std::string(e.what()), "cannot write '" + target.string() + "': disk on fire");
  }
  EXPECT_EQ(ReadBytes(target), original);
  EXPECT_EQ(dir.Entries(), std::vector<std::string>{"sky.exr"});
}

TEST(WriteFileAtomically, NonStandardExceptionIsAlsoConverted) {
  TempDir dir;
  EXPECT_THROW(WriteFileAtomically(dir / "x", [](const fs::path& t) {
                 WriteBytes(t, "x");
                 throw 42;
               }),
               Error);
  EXPECT_TRUE(dir.Entries().empty());
}

TEST(WriteFileAtomically, MissingDirectoryThrowsBeforeWritingAndCreatesNothing) {
  TempDir dir;
  const fs::path target = dir / "no" / "such" / "sky.exr";
  bool called = false;
  try {
    WriteFileAtomically(target, [&](const fs::path&) { called = true; });
    FAIL() << "no exception";
  } catch (const Error& e) {
    EXPECT_EQ(std::string(e.what()),
              "cannot write '" + target.string() + "': directory '" + (dir / "no" / "such").string() +
                  "' does not exist");
  }
  EXPECT_FALSE(called);
  EXPECT_TRUE(dir.Entries().empty());
}

TEST(Exr, WriteIntoMissingDirectoryThrowsMentioningThePathAndCreatesNothing) {
  TempDir dir;
  const fs::path target = dir / "missing" / "sky.exr";
  try {
    WriteExr(target, Image(2, 2, 3));
    FAIL() << "no exception";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find(target.string()), std::string::npos) << e.what();
  }
  EXPECT_TRUE(dir.Entries().empty());
}

TEST(WriteFileAtomically, TargetThatIsADirectoryThrows) {
  TempDir dir;
  fs::create_directory(dir / "sub");
  bool called = false;
  try {
    WriteFileAtomically(dir / "sub", [&](const fs::path&) { called = true; });
    FAIL() << "no exception";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("is a directory"), std::string::npos) << e.what();
  }
  EXPECT_FALSE(called);
  EXPECT_TRUE(fs::is_directory(dir / "sub"));
  EXPECT_EQ(dir.Entries(), std::vector<std::string>{"sub"});
  EXPECT_THROW(WriteExr(dir / "sub", Image(1, 1, 3)), Error);
  EXPECT_THROW(WritePng(dir / "sub", Image(1, 1, 3), ToneMapping{}), Error);
}

TEST(WriteFileAtomically, PathWithoutFileNameThrows) {
  TempDir dir;
  bool called = false;
  EXPECT_THROW(WriteFileAtomically(dir / "missing" / "", [&](const fs::path&) { called = true; }), Error);
  EXPECT_FALSE(called);
  EXPECT_TRUE(dir.Entries().empty());
}

TEST(WriteFileAtomically, ParentThatIsAFileThrows) {
  TempDir dir;
  WriteBytes(dir / "file", "x");
  EXPECT_THROW(WriteFileAtomically(dir / "file" / "out", [](const fs::path&) {}), Error);
}

TEST(WriteFileAtomically, ReadOnlyDirectoryThrowsBeforeWriting) {
  if (::geteuid() == 0) GTEST_SKIP() << "root can write anywhere";
  TempDir dir;
  fs::create_directory(dir / "ro");
  fs::permissions(dir / "ro", fs::perms::owner_read | fs::perms::owner_exec);
  bool called = false;
  try {
    WriteFileAtomically(dir / "ro" / "x", [&](const fs::path&) { called = true; });
    ADD_FAILURE() << "no exception";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("is not writable"), std::string::npos) << e.what();
  }
  EXPECT_FALSE(called);
  fs::permissions(dir / "ro", fs::perms::owner_all);
}

TEST(WriteFileAtomically, WriterThatCreatesNoFileThrows) {
  TempDir dir;
  WriteBytes(dir / "keep", "k");
  EXPECT_THROW(WriteFileAtomically(dir / "keep", [](const fs::path&) {}), Error);
  EXPECT_EQ(ReadBytes(dir / "keep"), "k");
}

TEST(WriteFileAtomically, RelativePathInCurrentDirectoryWorks) {
  TempDir dir;
  const fs::path previous = fs::current_path();
  fs::current_path(dir.path());
  WriteFileAtomically("plain.txt", [](const fs::path& t) { WriteBytes(t, "ok"); });
  fs::current_path(previous);
  EXPECT_EQ(ReadBytes(dir / "plain.txt"), "ok");
  EXPECT_EQ(dir.Entries(), std::vector<std::string>{"plain.txt"});
}

}  // namespace
}  // namespace atmo
