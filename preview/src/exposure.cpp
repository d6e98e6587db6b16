#include "afterglow/preview/exposure.h"

#include <algorithm>
#include <cmath>

#include "afterglow/core/math.h"
#include "afterglow/core/status.h"
#include "afterglow/runtime/probe_sh.h"

namespace afterglow::preview {

namespace {

// Below this fraction of the lights' scale a bake's bright texels are noise, not light: a lit
// bake's 99th percentile is within a few orders of magnitude of its sources' (the scale is
// taken across the level, bounced light is albedo × direct), and rounding and leaks through
// seams stay far below it.
constexpr float kBlackFraction = 1e-4f;

// World area per material over the static instances (what lights the bake).
std::vector<double> staticAreaPerMaterial(const scenes::Scene& scene) {
  std::vector<double> area(scene.materials.size(), 0.0);
  for (const scenes::Instance& inst : scene.instances) {
    const scenes::Mesh* mesh = scene.meshOf(inst);
    if (!inst.isStatic || !mesh) continue;
    scenes::forEachWorldTriangle(scene, inst, [&](size_t p, size_t, glm::vec3 a, glm::vec3 b,
                                                  glm::vec3 c) {
      const int m = mesh->primitives[p].material;
      const double triangle = 0.5 * double(glm::length(glm::cross(b - a, c - a)));
      if (m >= 0 && size_t(m) < area.size() && std::isfinite(triangle)) area[size_t(m)] += triangle;
    });
  }
  return area;
}

float skyScale(const baker::Environment& environment) {
  runtime::ShL2 sky;
  std::copy(environment.skySh, environment.skySh + runtime::kShCount, sky.c);
  float best = 0.0f;
  for (int axis = 0; axis < 6; ++axis) {
    glm::vec3 n(0.0f);
    n[axis / 2] = axis % 2 ? -1.0f : 1.0f;
    best = std::max(best, luminance(runtime::irradianceOverPi(sky, n)));
  }
  return best;
}

}  // namespace

Exposure chooseExposure(const std::vector<glm::vec3>& image, float exposureStops) {
  Exposure exposure;
  exposure.automatic = std::isnan(exposureStops);
  exposure.scale =
      exposure.automatic ? bakefiles::autoExposure(image) : std::exp2(exposureStops);
  exposure.stops = std::log2(exposure.scale);
  return exposure;
}

std::string describeExposure(const Exposure& exposure) {
  return format("%+.2f stops (x%.4g), %s", double(exposure.stops), double(exposure.scale),
                exposure.automatic
                    ? "automatic: the 99th percentile maps to 0.8 after the tone curve"
                    : "from --exposure");
}

float lightsScale(const scenes::Scene& scene, const baker::Environment& environment) {
  const glm::vec3 size = scene.staticBounds().size();
  const double reach = std::max(0.5 * double(std::max(size.x, std::max(size.y, size.z))), 1e-6);
  // E/π at `reach` is intensity / spread for a point light, radiance × area / spread for a
  // small emitter.
  const double spread = kPiDouble * reach * reach;
  double best = skyScale(environment);
  for (const scenes::Light& light : scene.lights) {
    const double intensity = double(luminance(light.color)) * double(light.intensity);
    best = std::max(best, light.type == scenes::LightType::Directional ? intensity / kPiDouble
                                                                       : intensity / spread);
  }
  const std::vector<double> area = staticAreaPerMaterial(scene);
  for (size_t m = 0; m < scene.materials.size(); ++m) {
    const double radiance = double(luminance(scene.materials[m].emission()));
    best = std::max(best, std::min(radiance, radiance * area[m] / spread));
  }
  return std::isfinite(best) ? float(best) : 0.0f;
}

float lightmapQuantile(const std::vector<bakefiles::LightmapImage>& lightmaps, double q) {
  std::vector<float> values;
  for (const bakefiles::LightmapImage& image : lightmaps)
    for (const glm::vec3& texel : image.pixels)
      if (const float l = luminance(texel); std::isfinite(l)) values.push_back(l);
  if (values.empty()) return 0.0f;
  const size_t k = std::min(values.size() - 1, size_t(double(values.size()) * q));
  std::nth_element(values.begin(), values.begin() + std::ptrdiff_t(k), values.end());
  return values[k];
}

std::string blackLightmapsWarning(const scenes::Scene& scene,
                                  const std::vector<bakefiles::LightmapImage>& lightmaps,
                                  const baker::Environment& environment, const std::string& name) {
  const float p99 = lightmapQuantile(lightmaps, 0.99);
  const float scale = lightsScale(scene, environment);
  if (!(scale > 0.0f))
    return p99 > 0.0f ? "" : name + ": the lightmaps are black: no light, emissive surface or sky "
                                    "lights the level";
  if (p99 >= kBlackFraction * scale) return "";
  return format("%s: the lightmaps are essentially black: their 99th percentile E/pi is %.3g, "
                "under 1e-4 of the lights' scale (E/pi %.3g, the brightest a light, emissive "
                "surface or the sky gives across the level); is the level closed to its only "
                "light (walls around it under a sky), or are its lights' intensities in the "
                "wrong units?",
                name.c_str(), double(p99), double(scale));
}

}  // namespace afterglow::preview
