// Tests of include/atmo/image.h: EXR round trips, PNG encoding, tone mapping, atomic writes.
#include <png.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <limits>
#include <random>
#include <stdexcept>
#include <string>
#include <vector>

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

// Decodes a PNG with libpng's simplified API into 8-bit RGB or RGBA.
std::vector<png_byte> DecodePng(const fs::path& path, bool rgba, int* width, int* height) {
  png_image png{};
  png.version = PNG_IMAGE_VERSION;
  if (!png_image_begin_read_from_file(&png, path.c_str())) throw std::runtime_error(png.message);
  png.format = rgba ? PNG_FORMAT_RGBA : PNG_FORMAT_RGB;
  std::vector<png_byte> bytes(PNG_IMAGE_SIZE(png));
  if (!png_image_finish_read(&png, nullptr, bytes.data(), 0, nullptr)) {
    png_image_free(&png);
    throw std::runtime_error(png.message);
  }
  *width = static_cast<int>(png.width);
  *height = static_cast<int>(png.height);
  return bytes;
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

TEST(Exr, NamedChannelsRoundTripInReadOrder) {
  // Extra channels "P.layer" come after R, G, B, grouped by layer in the order of P, whatever
  // order the image had (EXR itself stores channels sorted by name); the rest follow by name.
  TempDir dir;
  Image image = MakeTestImage(5, 4, 7, 8);
  image.channel_names = {"R", "G", "B", "B.stderr", "R.stderr", "G.stderr", "Z"};
  image.alpha.assign(5 * 4, 0.5f);
  WriteExr(dir / "named.exr", image);
  const Image read = ReadExr(dir / "named.exr");
  ASSERT_EQ(read.channels, 7);
  EXPECT_EQ(read.channel_names,
            (std::vector<std::string>{"R", "G", "B", "R.stderr", "G.stderr", "B.stderr", "Z"}));
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
  EXPECT_EQ(Image(1, 1, 3).ChannelIndex("R.stderr"), -1);
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

TEST(Png, DecodedBytesAreRoundedToneMappedValues) {
  TempDir dir;
  const ToneMapping mapping{ToneMapper::kExponential, 2.0, 2.2};
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
  const ToneMapping mapping{ToneMapper::kAces, 1.0, 2.2};
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
  const ToneMapping mapping{ToneMapper::kExponential, 10.0, 2.2};
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
    for (double gamma : {1.0, 2.2}) {
      const ToneMapping m{op, 3.0, gamma};
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
  const ToneMapping m{ToneMapper::kNone, 2.0, 1.0};
  EXPECT_FLOAT_EQ(ToneMapValue(0.25f, m), 0.5f);
  EXPECT_EQ(ToneMapValue(0.5f, m), 1.0f);
  EXPECT_EQ(ToneMapValue(7.0f, m), 1.0f);
  EXPECT_EQ(ToneMapValue(std::numeric_limits<float>::infinity(), m), 1.0f);
}

TEST(ToneMap, MatchesTheStatedCurves) {
  // Double-precision formulas of the header, rounded to float: a few ulps of float apart.
  const double x = 0.07, exposure = 10.0, v = exposure * x;
  EXPECT_NEAR(ToneMapValue(static_cast<float>(x), {ToneMapper::kExponential, exposure, 1.0}), 1.0 - std::exp(-v), 1e-6);
  EXPECT_NEAR(ToneMapValue(static_cast<float>(x), {ToneMapper::kAces, exposure, 1.0}),
              v * (2.51 * v + 0.03) / (v * (2.43 * v + 0.59) + 0.14), 1e-6);
}

TEST(ToneMap, GammaIsAPowerOfTheLinearResult) {
  for (ToneMapper op : {ToneMapper::kExponential, ToneMapper::kAces, ToneMapper::kNone}) {
    for (float x : {0.001f, 0.01f, 0.05f, 0.08f}) {
      const float linear = ToneMapValue(x, {op, 10.0, 1.0});
      const float encoded = ToneMapValue(x, {op, 10.0, 2.2});
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
      EXPECT_EQ(std::string(e.what()), "unknown tone mapper '" + std::string(name) + "' (use exp, aces or none)");
    }
  }
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
