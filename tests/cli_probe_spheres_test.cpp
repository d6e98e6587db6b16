// `afterglow render --probe-spheres` run as a user would: spheres lit by the light probes the
// bake wrote, checked against light known without the renderer (the furnace's Le / (1 − ρ)
// everywhere; half a sky over a grey ground, whose E/π grows linearly with the normal's
// height), at the probes they were drawn for, identical for any thread count, and refused with
// the missing file named when there are no probes.
#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "afterglow/trace/raytracer.h"
#include "afterglow/preview/render.h"
#include "afterglow/probes/probes_file.h"
#include "afterglow/probes/tetrahedralize.h"
#include "afterglow/scenes/gltf.h"
#include "afterglow/scenes/procedural.h"
#include "bake_fixtures.h"
#include "test_util.h"

namespace fs = std::filesystem;
using nlohmann::json;

namespace afterglow::test {
namespace {

constexpr float kAlbedo = 0.8f;  // the spheres' (preview::kProbeSphereAlbedo, as documented)

// A render's float RGB as written to an EXR, row 0 at the top.
// A render's linear RGB (through the renderer's own EXR reader), row 0 at the top; empty when
// it cannot be read.
struct LinearPicture {
  int width = 0, height = 0;
  std::vector<glm::vec3> pixels;
  glm::vec3 at(int x, int y) const { return pixels[size_t(y) * size_t(width) + size_t(x)]; }
};

LinearPicture readExr(const std::string& path) {
  Result<bakefiles::LightmapImage> image = bakefiles::readLinearImage(path);
  if (!image) return {};
  return {image->width, image->height, std::move(image->pixels)};
}

std::vector<glm::vec3> probePositions(const std::string& out) {
  Result<probes::ProbesFile> file = probes::readProbesFile(out + "/probes/light_probes.json");
  EXPECT_TRUE(file) << file.message();
  return file ? file->positions : std::vector<glm::vec3>();
}

// The probes named on the render's "spheres  N at probes a, b, ... (" line.
std::vector<int> spheresPrinted(const std::string& out) {
  std::vector<int> probes;
  const size_t at = out.find(" at probes ");
  if (at == std::string::npos) return probes;
  std::istringstream list(out.substr(at + 11, out.find('(', at) - at - 11));
  for (std::string item; std::getline(list, item, ',');) probes.push_back(std::stoi(item));
  return probes;
}

// The picture point of p in a width × height picture of view (render.h's camera model).
glm::vec2 project(const trace::View& view, int width, int height, glm::vec3 p) {
  const glm::vec3 right = glm::normalize(glm::cross(view.forward, view.up));
  const glm::vec3 d = p - view.position;
  const float z = glm::dot(d, view.forward), t = std::tan(0.5f * view.yfov);
  return {(glm::dot(d, right) / (z * t * float(width) / float(height)) * 0.5f + 0.5f) *
              float(width),
          (0.5f - glm::dot(d, view.up) / (z * t) * 0.5f) * float(height)};
}

bool near(glm::vec3 value, glm::vec3 expected, float relative) {
  for (int k = 0; k < 3; ++k)
    if (!(std::abs(value[k] - expected[k]) <= relative * expected[k])) return false;
  return true;
}

// The white furnace (base colour 0.5, so ρ = 0.96 × 0.5 + 0.02 = 0.5, and Le = 1): every probe
// sees 2 from every direction, so a sphere shows 0.8 × 2 = 1.6 all over, whatever its normal,
// and the walls (albedo × E/π + Le) show 2. A sphere is told from a wall by its value alone:
// at the centre of every sphere the render names, and nowhere outside [1.6, 2] (a wrong factor
// of π, albedo or unit, or the lightmap's E/π in place of the probes', fails).
TEST(CliProbeSpheres, FurnaceSpheresAreAlbedoTimesLeOverOneMinusRho) {
  const std::string dir = tempDir("cli_probe_spheres_furnace");
  const std::string out = dir + "/out";
  // Without reflection probes, so that every sphere is white and diffuse (with them, every
  // second and third is a metal).
  CliRun bake = runCli(dir, "bake builtin:furnace -o '" + out +
                                "' --quality draft --reflection-probes none --quiet");
  ASSERT_EQ(bake.exitCode, 0) << bake.err;
  const std::vector<glm::vec3> positions = probePositions(out);
  ASSERT_GT(positions.size(), 8u);
  const int size = 128;
  const std::string view = "render '" + out + "/scene.gltf' --width 128 --height 128 ";
  CliRun handful = runCli(dir, view + "--probe-spheres -o '" + dir + "/handful.exr'");
  ASSERT_EQ(handful.exitCode, 0) << handful.err;
  CliRun all = runCli(dir, view + "--probe-spheres all -o '" + dir + "/all.exr'");
  ASSERT_EQ(all.exitCode, 0) << all.err;
  EXPECT_NE(all.out.find("at every probe"), std::string::npos) << all.out;

  const glm::vec3 sphere(kAlbedo * 2.0f), wall(2.0f);
  // The furnace's camera: at the box's centre, looking down −Z, 90°.
  const trace::View camera = trace::cameraView(scenes::makeFurnaceBox().cameras.front());
  const std::vector<int> drawn = spheresPrinted(handful.out);
  EXPECT_EQ(drawn.size(), 8u) << handful.out;
  const LinearPicture picture = readExr(dir + "/handful.exr");
  ASSERT_EQ(picture.width, size);
  for (int probe : drawn) {
    ASSERT_LT(size_t(probe), positions.size());
    const glm::vec2 p = project(camera, size, size, positions[size_t(probe)]);
    ASSERT_TRUE(p.x >= 0.0f && p.y >= 0.0f && p.x < float(size) && p.y < float(size)) << probe;
    const glm::vec3 v = picture.at(int(p.x), int(p.y));
    EXPECT_TRUE(near(v, sphere, 0.02f))
        << "probe " << probe << " at pixel " << p.x << ", " << p.y << ": " << v.x;
  }

  for (const char* name : {"handful.exr", "all.exr"}) {
    const LinearPicture e = readExr(dir + "/" + name);
    ASSERT_EQ(e.width, size) << name;
    size_t spherePixels = 0, wallPixels = 0;
    float lo = 1e9f, hi = 0.0f;
    for (int y = 0; y < size; ++y)
      for (int x = 0; x < size; ++x) {
        const glm::vec3 v = e.at(x, y);
        lo = std::min({lo, v.x, v.y, v.z});
        hi = std::max({hi, v.x, v.y, v.z});
        spherePixels += near(v, sphere, 0.02f);
        wallPixels += near(v, wall, 0.02f);
      }
    EXPECT_GE(lo, sphere.x * 0.98f) << name;
    // (A draft bake's walls are within 8%; its probes within 1%.)
    EXPECT_LE(hi, wall.x * 1.1f) << name;
    EXPECT_GT(spherePixels, 100u) << name;
    EXPECT_GT(wallPixels, size_t(size * size / 4)) << name;
  }
}

// A grey ground (ρ = 0.5) far wider than high under a constant sky L, and nothing else: a probe
// above it sees L over the upper hemisphere and the ground's 0.5 L below, so a sphere's
// E(n)/π = L (1 + n_y) / 2 + 0.5 L (1 − n_y) / 2 = L (0.75 + 0.25 n_y), exactly in L2 SH (band 2
// is zero, band 1 linear). Every pixel well inside a sphere (all four of its rays on it) is
// 0.8 × that, averaged over its rays, within 2%: a flipped, mirrored or misplaced normal, a
// sphere drawn off its probe, or a wrong size fails. (Measured: 1.7% at worst, the probes' own
// quadrature of the sharp horizon: E/π sideways is 0.743 to 0.757 L for 0.75 L.)
TEST(CliProbeSpheres, UnderHalfASkyEachNormalGetsItsAnalyticIrradiance) {
  const std::string dir = tempDir("cli_probe_spheres_sky");
  // Base colour 0.5, default specular: ρ = 0.96 × 0.5 + 0.02 = 0.5. 1 km a side: the gap under
  // the horizon is 2/1000 rad from the higher probes.
  const scenes::Scene ground = baker::groundQuad("ground", 1000.0f, 0.5f);
  Status saved = scenes::saveGltf(ground, dir + "/ground.gltf");
  ASSERT_TRUE(saved) << saved.message();

  // A cube of probes 1 m apart, 1 to 2 m above the ground: spheres of 0.2 m (a fifth of the
  // spacing) that the ground is too far below to shrink.
  probes::Placement placement;
  for (float y : {1.0f, 2.0f})
    for (float z : {-0.5f, 0.5f})
      for (float x : {-0.5f, 0.5f}) {
        placement.positions.push_back({x, y, z});
        placement.kinds.push_back(probes::ProbeKind::Pinned);
      }
  Result<runtime::ProbeTetrahedra> mesh4 = probes::tetrahedralize(placement.positions);
  ASSERT_TRUE(mesh4) << mesh4.message();
  std::ofstream(dir + "/probes.json")
      << probes::probesJson(placement, std::vector<std::string>(placement.positions.size()),
                            mesh4.value(), "{}", "{}");

  const glm::vec3 sky(0.3f, 0.5f, 0.9f);
  const std::string out = dir + "/out";
  CliRun bake = runCli(dir, "bake '" + dir + "/ground.gltf' -o '" + out +
                                "' --sky 0.3,0.5,0.9 --probes '" + dir +
                                "/probes.json' --texels-per-unit 0.01 --quality draft --quiet");
  ASSERT_EQ(bake.exitCode, 0) << bake.err;
  const int width = 160, height = 120;
  const glm::vec3 from(0.0f, 1.5f, -4.0f), at(0.0f, 1.5f, 0.0f);
  CliRun render = runCli(dir, "render '" + out + "/scene.gltf' --look-from 0,1.5,-4 "
                              "--look-at 0,1.5,0 --fov 40 --width 160 --height 120 "
                              "--probe-spheres all -o '" + dir + "/view.exr' --quiet");
  ASSERT_EQ(render.exitCode, 0) << render.err;
  const LinearPicture e = readExr(dir + "/view.exr");
  ASSERT_EQ(e.width, width);
  ASSERT_EQ(e.height, height);

  const trace::View view = trace::lookAtView(from, at, 40.0f * 3.14159265f / 180.0f);
  const float radius = 0.2f;
  size_t checked = 0;
  float worst = 0.0f;
  // The four nearer spheres, in front of the four behind them.
  for (const glm::vec3& p : placement.positions) {
    if (p.z > 0.0f) continue;
    const glm::vec2 c = project(view, width, height, p);
    for (int y = int(c.y) - 15; y <= int(c.y) + 15; ++y)
      for (int x = int(c.x) - 15; x <= int(c.x) + 15; ++x) {
        if (x < 0 || y < 0 || x >= width || y >= height) continue;
        // The render's 2 × 2 rays per pixel, each shaded with its own normal.
        glm::vec3 expected(0.0f);
        bool inside = true;
        for (int sy = 0; sy < 2 && inside; ++sy)
          for (int sx = 0; sx < 2 && inside; ++sx) {
            const trace::Ray ray =
                trace::cameraRay(view, width, height, float(x) + 0.25f + 0.5f * float(sx),
                                 float(y) + 0.25f + 0.5f * float(sy));
            const glm::vec3 oc = ray.origin - p;
            const float b = glm::dot(oc, ray.direction);
            const glm::vec3 across = oc - b * ray.direction;
            const float miss2 = glm::dot(across, across);
            // Well inside the outline: the edge's pixels mix in what lies behind.
            if (miss2 > 0.8f * 0.8f * radius * radius) {
              inside = false;
              break;
            }
            const float t = -b - std::sqrt(radius * radius - miss2);
            const glm::vec3 n = glm::normalize(ray.origin + t * ray.direction - p);
            expected += 0.25f * kAlbedo * sky * (0.75f + 0.25f * n.y);
          }
        if (!inside) continue;
        ++checked;
        const glm::vec3 v = e.at(x, y);
        for (int k = 0; k < 3; ++k) worst = std::max(worst, std::abs(v[k] / expected[k] - 1.0f));
        EXPECT_TRUE(near(v, expected, 0.02f))
            << "pixel " << x << ", " << y << ": " << v.x << " " << v.y << " " << v.z
            << ", expected " << expected.x << " " << expected.y << " " << expected.z;
      }
  }
  EXPECT_GT(checked, 200u);
  std::printf("probe spheres under half a sky: %zu pixels, worst relative error %.4f\n", checked,
              double(worst));
}

// A draft bake of the Cornell box for the tests below.
std::string bakeCornell(const std::string& dir) {
  const std::string out = dir + "/out";
  CliRun r = runCli(dir, "bake builtin:cornell -o '" + out +
                              "' --quality draft --texels-per-unit 48 --quiet");
  EXPECT_EQ(r.exitCode, 0) << r.err;
  return out;
}

// The spheres (their choice, shading and the tiles that find them) do not depend on the thread
// count: the EXRs of one and two threads are bit for bit the same. --probe-spheres before the
// scene leaves the scene in place (it takes only a count or "all" as its value).
TEST(CliProbeSpheres, SameForOneAndTwoThreads) {
  const std::string dir = tempDir("cli_probe_spheres_threads");
  const std::string out = bakeCornell(dir);
  for (const char* count : {"", "all"}) {
    const std::string view = std::string("render --probe-spheres ") + count + " '" + out +
                             "/scene.gltf' --width 96 --height 72 --quiet ";
    ASSERT_EQ(runCli(dir, view + "--threads 1 -o '" + dir + "/one.exr'").exitCode, 0) << count;
    ASSERT_EQ(runCli(dir, view + "--threads 2 -o '" + dir + "/two.exr'").exitCode, 0) << count;
    const LinearPicture one = readExr(dir + "/one.exr"), two = readExr(dir + "/two.exr");
    ASSERT_EQ(one.pixels.size(), size_t(96 * 72)) << count;
    EXPECT_TRUE(one.pixels == two.pixels) << count;
  }
  // The PNG too, and the spheres change the picture.
  const std::string view =
      "render '" + out + "/scene.gltf' --width 96 --height 72 --quiet -o '" + dir;
  ASSERT_EQ(runCli(dir, view + "/plain.exr'").exitCode, 0);
  EXPECT_FALSE(readExr(dir + "/plain.exr").pixels == readExr(dir + "/one.exr").pixels);
  ASSERT_EQ(runCli(dir, view + "/spheres.png' --probe-spheres 3").exitCode, 0);
  EXPECT_TRUE(fs::exists(dir + "/spheres.png"));
}

// Without the probes' files the render names the one missing and writes nothing; a built-in
// scene (no bake folder), --reference and a count of 0 are usage errors.
TEST(CliProbeSpheres, MissingProbesAreNamedAndNothingIsWritten) {
  const std::string dir = tempDir("cli_probe_spheres_missing");
  const std::string out = bakeCornell(dir);
  fs::remove(out + "/probes/light_probes_sh.bin");
  CliRun missing =
      runCli(dir, "render '" + out + "/scene.gltf' --probe-spheres -o '" + dir + "/view.png'");
  EXPECT_EQ(missing.exitCode, 1);
  EXPECT_NE(missing.err.find("light_probes_sh.bin"), std::string::npos) << missing.err;
  EXPECT_FALSE(fs::exists(dir + "/view.png"));

  CliRun builtin = runCli(dir, "render builtin:cornell --probe-spheres -o '" + dir + "/b.png'");
  EXPECT_EQ(builtin.exitCode, 2);
  EXPECT_NE(builtin.err.find("afterglow bake"), std::string::npos) << builtin.err;
  CliRun reference = runCli(dir, "render '" + out + "/scene.gltf' --probe-spheres --reference "
                                 "-o '" + dir + "/r.png'");
  EXPECT_EQ(reference.exitCode, 2);
  CliRun zero = runCli(dir, "render '" + out + "/scene.gltf' --probe-spheres 0 -o '" + dir +
                                "/z.png'");
  EXPECT_EQ(zero.exitCode, 2);
  EXPECT_NE(zero.err.find("all"), std::string::npos) << zero.err;
  EXPECT_FALSE(fs::exists(dir + "/b.png") || fs::exists(dir + "/r.png") ||
               fs::exists(dir + "/z.png"));
}

}  // namespace
}  // namespace afterglow::test
