// The reflection probes' EXR files (baker/reflection_exr.h): the cube environment map with its
// mip levels read back through OpenImageIO, checked against OpenEXR's own ImfEnvmap (when its
// headers are installed), the DFG table, and bad input that must write nothing.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <random>

#include <OpenImageIO/imageio.h>

#include "afterglow/bakefiles/cube_exr.h"
#include "afterglow/runtime/reflection_prefilter.h"
#include "test_util.h"

#ifdef AFTERGLOW_HAVE_OPENEXR
#include <OpenEXR/ImfEnvmap.h>
#include <OpenEXR/ImfHeader.h>
#include <OpenEXR/ImfStandardAttributes.h>
#include <OpenEXR/ImfTiledInputFile.h>
#endif

namespace fs = std::filesystem;

namespace afterglow::bakefiles {
namespace {

// A chain of `count` mips of a size² cube, every texel a distinct value in (0, 8).
std::vector<runtime::Cubemap> randomChain(int size, int count, uint32_t seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> value(0.01f, 8.0f);
  std::vector<runtime::Cubemap> mips;
  for (int m = 0; m < count; ++m) {
    runtime::Cubemap c = runtime::makeCubemap(size >> m);
    for (glm::vec3& t : c.texels) t = {value(rng), value(rng), value(rng)};
    mips.push_back(std::move(c));
  }
  return mips;
}

// A cube whose every texel holds the direction through its centre, mapped into (0, 2).
runtime::Cubemap directionCube(int size) {
  runtime::Cubemap c = runtime::makeCubemap(size);
  for (int f = 0; f < runtime::kCubeFaceCount; ++f)
    for (int y = 0; y < size; ++y)
      for (int x = 0; x < size; ++x)
        c.at(f, x, y) = runtime::cubemapTexelDirection(f, x, y, size) + glm::vec3(1.0f);
  return c;
}

bool anyFileIn(const std::string& dir) {
  std::error_code ec;
  if (!fs::exists(dir, ec)) return false;
  return fs::directory_iterator(dir) != fs::directory_iterator();
}

// Seven prefiltered mips of a 128² probe, as the bake writes them: every mip back exactly (in
// float) and OpenEXR's ten levels readable, the last three the filler the format needs.
TEST(ReflectionExr, CubeRoundTripsSevenMipsThroughOpenImageIO) {
  const std::string dir = test::tempDir("reflection_exr_roundtrip");
  const std::string path = dir + "/probe.exr";
  const std::vector<runtime::Cubemap> mips = randomChain(128, 7, 1);
  ASSERT_TRUE(writeCubemapExr(path, mips, ExrPixels::Float).isOk());

  auto in = OIIO::ImageInput::open(path);
  ASSERT_TRUE(in) << OIIO::geterror();
  EXPECT_EQ(in->spec().get_string_attribute("textureformat"), "CubeFace Environment");
  EXPECT_EQ(in->spec().get_int_attribute("afterglow:prefilteredLevels"), 7);
  EXPECT_EQ(in->spec().tile_width, 64);
  const int expected[10][2] = {{128, 768}, {64, 384}, {32, 192}, {16, 96}, {8, 48},
                               {4, 24},    {2, 12},   {1, 6},    {1, 3},   {1, 1}};
  int levels = 0;
  while (in->seek_subimage(0, levels)) {
    ASSERT_LT(levels, 10);
    EXPECT_EQ(in->spec().width, expected[levels][0]) << "level " << levels;
    EXPECT_EQ(in->spec().height, expected[levels][1]) << "level " << levels;
    std::vector<float> pixels(size_t(in->spec().width) * size_t(in->spec().height) * 3);
    EXPECT_TRUE(in->read_image(0, levels, 0, 3, OIIO::TypeDesc::FLOAT, pixels.data()))
        << "level " << levels << ": " << in->geterror();
    if (levels == 7) {
      // 1×6: each face the mean of the 2² face of mip 6.
      for (int f = 0; f < 6; ++f) {
        glm::vec3 mean(0.0f);
        for (int y = 0; y < 2; ++y)
          for (int x = 0; x < 2; ++x) mean += mips[6].at(f, x, y) / 4.0f;
        EXPECT_NEAR(pixels[size_t(f) * 3], mean.r, 1e-5f) << "face " << f;
      }
    }
    ++levels;
  }
  EXPECT_EQ(levels, 10);
  in.reset();

  Result<std::vector<runtime::Cubemap>> back = readCubemapExr(path);
  ASSERT_TRUE(back.isOk()) << back.message();
  ASSERT_EQ(back->size(), 7u);
  for (int m = 0; m < 7; ++m) {
    ASSERT_EQ((*back)[size_t(m)].size, 128 >> m);
    EXPECT_EQ((*back)[size_t(m)].texels, mips[size_t(m)].texels) << "mip " << m;
  }
  // No temporary left beside it.
  int files = 0;
  for (const auto& e : fs::directory_iterator(dir)) files += e.is_regular_file() ? 1 : 0;
  EXPECT_EQ(files, 1);
}

// Half floats keep a value to half's precision; values past half's range are clamped to its
// largest finite value instead of becoming infinities.
TEST(ReflectionExr, HalfKeepsValuesAndClampsTheOutOfRange) {
  const std::string dir = test::tempDir("reflection_exr_half");
  std::vector<runtime::Cubemap> mips = randomChain(16, 5, 2);
  mips[0].at(runtime::kCubeFacePosY, 3, 4) = glm::vec3(1e6f, 70000.0f, 5.0f);
  ASSERT_TRUE(writeCubemapExr(dir + "/probe.exr", mips).isOk());
  Result<std::vector<runtime::Cubemap>> back = readCubemapExr(dir + "/probe.exr");
  ASSERT_TRUE(back.isOk()) << back.message();
  ASSERT_EQ(back->size(), 5u);
  for (int m = 0; m < 5; ++m)
    for (size_t i = 0; i < mips[size_t(m)].texels.size(); ++i) {
      const glm::vec3 a = mips[size_t(m)].texels[i], b = (*back)[size_t(m)].texels[i];
      for (int k = 0; k < 3; ++k)
        EXPECT_NEAR(b[k], std::min(a[k], 65504.0f), std::min(a[k], 65504.0f) * 1e-3f);
    }
  EXPECT_EQ((*back)[0].at(runtime::kCubeFacePosY, 3, 4).x, 65504.0f);
}

#ifdef AFTERGLOW_HAVE_OPENEXR
// The file as OpenEXR itself reads it: envmap = ENVMAP_CUBE, MIPMAP_LEVELS rounded down, and
// the face layout: for directions through texel centres, Imf::CubeMap's faceAndPixelPosition and
// pixelPosition (the library's definition of a cube map) land on the pixel that holds the texel
// runtime::cubemapTexel gives. This is what exrenvmap and every ImfEnvmap reader see.
TEST(ReflectionExr, OpenExrSeesACubeMapWithOurFaces) {
  const std::string dir = test::tempDir("reflection_exr_openexr");
  const std::string path = dir + "/probe.exr";
  const int size = 16;
  std::vector<runtime::Cubemap> mips = {directionCube(size), directionCube(size / 2)};
  ASSERT_TRUE(writeCubemapExr(path, mips, ExrPixels::Float).isOk());

  Imf::TiledInputFile file(path.c_str());
  const Imf::Header& header = file.header();
  ASSERT_TRUE(Imf::hasEnvmap(header));
  EXPECT_EQ(Imf::envmap(header), Imf::ENVMAP_CUBE);
  EXPECT_EQ(file.levelMode(), Imf::MIPMAP_LEVELS);
  EXPECT_EQ(file.levelRoundingMode(), Imf::ROUND_DOWN);
  EXPECT_EQ(file.numLevels(), 7);  // 16×96 .. 1×1
  const Imath::Box2i dw = header.dataWindow();
  EXPECT_EQ(dw.max.x - dw.min.x + 1, size);
  EXPECT_EQ(dw.max.y - dw.min.y + 1, 6 * size);
  EXPECT_EQ(Imf::CubeMap::sizeOfFace(dw), size);

  auto in = OIIO::ImageInput::open(path);
  ASSERT_TRUE(in);
  std::vector<glm::vec3> pixels(size_t(size) * size_t(6 * size));
  ASSERT_TRUE(in->read_image(0, 0, 0, 3, OIIO::TypeDesc::FLOAT, pixels.data()));
  std::mt19937 rng(3);
  std::uniform_int_distribution<int> pick(0, size - 1);
  int checked = 0;
  for (int face = 0; face < 6; ++face)
    for (int k = 0; k < 40; ++k) {
      const int x = pick(rng), y = pick(rng);
      const glm::vec3 d = runtime::cubemapTexelDirection(face, x, y, size);
      Imf::CubeMapFace exrFace;
      Imath::V2f inFace;
      Imf::CubeMap::faceAndPixelPosition(Imath::V3f(d.x, d.y, d.z), dw, exrFace, inFace);
      EXPECT_EQ(int(exrFace), face);
      const Imath::V2f pos = Imf::CubeMap::pixelPosition(exrFace, dw, inFace);
      const int px = int(std::lround(pos.x)), py = int(std::lround(pos.y));
      ASSERT_GE(px, 0);
      ASSERT_LT(px, size);
      ASSERT_GE(py, 0);
      ASSERT_LT(py, 6 * size);
      const glm::vec3 stored = pixels[size_t(py) * size_t(size) + size_t(px)] - glm::vec3(1.0f);
      EXPECT_LT(glm::length(stored - d), 1e-5f)
          << "face " << face << " texel " << x << "," << y << " read at " << px << "," << py;
      // And OpenEXR's direction for that pixel is within half a texel of ours (its edge-texel
      // convention, runtime/cubemap.h).
      const Imath::V3f back = Imf::CubeMap::direction(exrFace, dw, inFace).normalized();
      EXPECT_LT(std::acos(std::min(1.0f, back.dot(Imath::V3f(d.x, d.y, d.z)))), 2.0f / size);
      ++checked;
    }
  EXPECT_EQ(checked, 240);
}
#else
TEST(ReflectionExr, OpenExrSeesACubeMapWithOurFaces) {
  GTEST_SKIP() << "OpenEXR's headers are absent (libopenexr-dev): ImfEnvmap check skipped";
}
#endif

TEST(ReflectionExr, DfgTableRoundTrips) {
  const std::string dir = test::tempDir("reflection_exr_dfg");
  const std::string path = dir + "/dfg.exr";
  const int size = 64;
  const std::vector<glm::vec2> table = runtime::dfgTable(size, 64);
  ASSERT_TRUE(writeDfgExr(path, table, size).isOk());
  auto in = OIIO::ImageInput::open(path);
  ASSERT_TRUE(in) << OIIO::geterror();
  const OIIO::ImageSpec& spec = in->spec();
  EXPECT_EQ(spec.width, size);
  EXPECT_EQ(spec.height, size);
  EXPECT_EQ(spec.nchannels, 3);
  EXPECT_EQ(spec.format, OIIO::TypeDesc::FLOAT);
  std::vector<float> pixels(size_t(size) * size_t(size) * 3);
  ASSERT_TRUE(in->read_image(0, 0, 0, 3, OIIO::TypeDesc::FLOAT, pixels.data()));
  for (size_t i = 0; i < table.size(); ++i) {
    EXPECT_EQ(pixels[i * 3 + 0], table[i].x);
    EXPECT_EQ(pixels[i * 3 + 1], table[i].y);
    EXPECT_EQ(pixels[i * 3 + 2], 0.0f);
  }
  // Row 0 is the smoothest: at r ≈ 0 and NdotV → 1 the BRDF is a mirror, scale + bias ≈ 1.
  EXPECT_GT(pixels[size_t(size - 1) * 3] + pixels[size_t(size - 1) * 3 + 1], 0.95f);
  // The last row (r ≈ 1) reflects less at grazing NdotV than the first.
  const size_t lastRowFirst = size_t(size - 1) * size_t(size) * 3;
  EXPECT_LT(pixels[lastRowFirst] + pixels[lastRowFirst + 1], pixels[0] + pixels[1]);
}

// A missing folder is an error naming the path, and nothing appears (not even the folder).
TEST(ReflectionExr, MissingFolderWritesNothing) {
  const std::string dir = test::tempDir("reflection_exr_missing");
  const std::string path = dir + "/no/such/folder/probe.exr";
  Status s = writeCubemapExr(path, randomChain(8, 2, 4));
  ASSERT_FALSE(s.isOk());
  EXPECT_NE(s.message().find(path), std::string::npos) << s.message();
  EXPECT_FALSE(anyFileIn(dir));
  const std::string dfg = dir + "/missing/dfg.exr";
  s = writeDfgExr(dfg, runtime::dfgTable(4, 16), 4);
  ASSERT_FALSE(s.isOk());
  EXPECT_NE(s.message().find(dfg), std::string::npos) << s.message();
  EXPECT_FALSE(anyFileIn(dir));
}

// Through the bake's AtomicOutput (which creates folders) a folder that cannot be made, a file
// standing where it should be, fails naming the path and leaves no temporary behind.
TEST(ReflectionExr, UnwritablePathThroughAtomicOutputLeavesNothing) {
  const std::string dir = test::tempDir("reflection_exr_unwritable");
  std::ofstream(dir + "/probes") << "a file, not a folder";
  const std::string path = dir + "/probes/probe.exr";
  {
    AtomicOutput out;
    Status s = writeCubemapExr(path, randomChain(8, 2, 5), out);
    ASSERT_FALSE(s.isOk());
    EXPECT_NE(s.message().find(path), std::string::npos) << s.message();
  }
  int entries = 0;
  for (const auto& e : fs::directory_iterator(dir)) entries += e.path().filename() != "probes";
  EXPECT_EQ(entries, 0);
}

TEST(ReflectionExr, BadChainsAreRefusedNamingTheFault) {
  const std::string dir = test::tempDir("reflection_exr_bad");
  const std::string path = dir + "/probe.exr";
  auto refuse = [&](const std::vector<runtime::Cubemap>& mips, const std::string& words) {
    Status s = writeCubemapExr(path, mips);
    ASSERT_FALSE(s.isOk()) << words;
    EXPECT_NE(s.message().find(path), std::string::npos) << s.message();
    EXPECT_NE(s.message().find(words), std::string::npos) << s.message();
    EXPECT_FALSE(anyFileIn(dir)) << words;
  };
  refuse({}, "no mips");
  std::vector<runtime::Cubemap> skipped = randomChain(16, 3, 6);
  skipped[2] = runtime::makeCubemap(2);
  refuse(skipped, "mip 2 has size 2");
  // 24 = 3·8: four mips are fine (24, 12, 6, 3), five would need 24 divisible by 16.
  std::vector<runtime::Cubemap> odd;
  for (int s : {24, 12, 6, 3, 1}) odd.push_back(runtime::makeCubemap(s, glm::vec3(1.0f)));
  refuse(odd, "divisible by 2^4");
  odd.pop_back();
  EXPECT_TRUE(writeCubemapExr(path, odd).isOk());
  fs::remove(path);
  std::vector<runtime::Cubemap> nan = randomChain(8, 2, 7);
  nan[1].at(runtime::kCubeFaceNegZ, 1, 2).g = std::nanf("");
  refuse(nan, "mip 1 face -Z texel (1, 2) is not finite");
  Status s = writeDfgExr(dir + "/dfg.exr", std::vector<glm::vec2>(10), 4);
  EXPECT_FALSE(s.isOk());
  EXPECT_FALSE(anyFileIn(dir));
}

TEST(ReflectionExr, ReaderRefusesWhatIsNoCubeMap) {
  const std::string dir = test::tempDir("reflection_exr_reader");
  Result<std::vector<runtime::Cubemap>> r = readCubemapExr(dir + "/absent.exr");
  ASSERT_FALSE(r.isOk());
  EXPECT_NE(r.message().find("absent.exr"), std::string::npos) << r.message();
  // A plain 8 × 48 EXR (no envmap attribute) is not taken for a cube map.
  const std::string plain = dir + "/plain.exr";
  {
    auto out = OIIO::ImageOutput::create(plain);
    OIIO::ImageSpec spec(8, 48, 3, OIIO::TypeDesc::FLOAT);
    std::vector<float> px(8 * 48 * 3, 1.0f);
    ASSERT_TRUE(out->open(plain, spec) && out->write_image(OIIO::TypeDesc::FLOAT, px.data()) &&
                out->close());
  }
  r = readCubemapExr(plain);
  ASSERT_FALSE(r.isOk());
  EXPECT_NE(r.message().find("not an OpenEXR cube environment map"), std::string::npos)
      << r.message();
}

}  // namespace
}  // namespace afterglow::bakefiles
