#include "afterglow/baker/render.h"

#include <algorithm>
#include <cmath>
#include <filesystem>

#include <OpenImageIO/imageio.h>
#include <nlohmann/json.hpp>

#include "afterglow/baker/clusters.h"
#include "afterglow/baker/raytracer.h"
#include "afterglow/core/atomic_file.h"
#include "afterglow/core/parallel.h"
#include "afterglow/baker/bake_output.h"

namespace fs = std::filesystem;
using nlohmann::json;

namespace afterglow::baker {

namespace {

Result<LightmapImage> readExr(const std::string& path) {
  auto in = OIIO::ImageInput::open(path);
  if (!in) return Status::error(path + ": cannot read the lightmap (" + OIIO::geterror() + ")");
  const OIIO::ImageSpec spec = in->spec();
  LightmapImage image;
  image.width = spec.width;
  image.height = spec.height;
  const int channels = spec.nchannels;
  if (image.width <= 0 || image.height <= 0 || channels < 1)
    return Status::error(path + ": empty lightmap");
  std::vector<float> data(size_t(image.width) * size_t(image.height) * size_t(channels));
  if (!in->read_image(0, 0, 0, channels, OIIO::TypeDesc::FLOAT, data.data()))
    return Status::error(path + ": cannot decode the lightmap (" + in->geterror() + ")");
  image.pixels.resize(size_t(image.width) * size_t(image.height));
  for (size_t i = 0; i < image.pixels.size(); ++i) {
    const float* p = &data[i * size_t(channels)];
    image.pixels[i] = channels >= 3 ? glm::vec3(p[0], p[1], p[2]) : glm::vec3(p[0]);
  }
  return image;
}

// Bilinear between texel centres, clamped at the edges (the bake dilated into the padding).
glm::vec3 fetch(const LightmapImage& lm, glm::vec2 uv) {
  const float x = uv.x * float(lm.width) - 0.5f, y = uv.y * float(lm.height) - 0.5f;
  const float fx = std::floor(x), fy = std::floor(y);
  const float tx = x - fx, ty = y - fy;
  auto at = [&](int px, int py) {
    px = std::clamp(px, 0, lm.width - 1);
    py = std::clamp(py, 0, lm.height - 1);
    return lm.pixels[size_t(py) * size_t(lm.width) + size_t(px)];
  };
  const int x0 = int(fx), y0 = int(fy);
  return glm::mix(glm::mix(at(x0, y0), at(x0 + 1, y0), tx),
                  glm::mix(at(x0, y0 + 1), at(x0 + 1, y0 + 1), tx), ty);
}

}  // namespace

View cameraView(const scenes::Camera& camera) {
  View v;
  v.position = glm::vec3(camera.transform * glm::vec4(0.0f, 0.0f, 0.0f, 1.0f));
  v.forward = glm::normalize(glm::vec3(camera.transform * glm::vec4(0.0f, 0.0f, -1.0f, 0.0f)));
  glm::vec3 up = glm::vec3(camera.transform * glm::vec4(0.0f, 1.0f, 0.0f, 0.0f));
  up -= v.forward * glm::dot(up, v.forward);
  v.up = glm::length(up) > 1e-6f ? glm::normalize(up) : glm::vec3(0.0f, 1.0f, 0.0f);
  v.yfov = camera.perspective ? camera.yfov : 0.8f;
  return v;
}

View lookAtView(glm::vec3 from, glm::vec3 at, float yfov) {
  View v;
  v.position = from;
  glm::vec3 f = at - from;
  v.forward = glm::length(f) > 0.0f ? glm::normalize(f) : glm::vec3(0.0f, 0.0f, -1.0f);
  glm::vec3 up(0.0f, 1.0f, 0.0f);
  if (std::abs(glm::dot(up, v.forward)) > 0.999f) up = glm::vec3(0.0f, 0.0f, 1.0f);
  v.up = glm::normalize(up - v.forward * glm::dot(up, v.forward));
  v.yfov = yfov;
  return v;
}

View defaultView(const scenes::Scene& scene, float yfov) {
  const scenes::Bounds b = scene.bounds();
  if (b.empty()) return lookAtView(glm::vec3(0.0f, 0.0f, 1.0f), glm::vec3(0.0f), yfov);
  const glm::vec3 centre = (b.min + b.max) * 0.5f;
  const float radius = glm::length(b.size()) * 0.5f;
  const float distance = radius / std::tan(yfov * 0.5f) * 1.1f;
  // From above and to the side, so floors and walls both show.
  return lookAtView(centre + glm::normalize(glm::vec3(0.4f, 0.6f, -1.0f)) * distance, centre, yfov);
}

Result<std::vector<LightmapImage>> loadBakedLightmaps(const std::string& gltfPath) {
  Result<std::string> text = readFile(gltfPath);
  if (!text) return text.status();
  const json doc = json::parse(text.value(), nullptr, false);
  if (doc.is_discarded()) return Status::error(gltfPath + ": not valid JSON");
  std::vector<std::string> files;  // per atlas, relative to the glTF
  if (doc.contains("extras") && doc["extras"].contains("afterglow") &&
      doc["extras"]["afterglow"].contains("lightmaps")) {
    for (const json& entry : doc["extras"]["afterglow"]["lightmaps"])
      files.push_back(entry.value("exr", std::string()));
  } else if (doc.contains("materials")) {
    for (const json& mat : doc["materials"]) {
      if (!mat.contains("extensions") || !mat["extensions"].contains("MOZ_lightmap")) continue;
      const json& ext = mat["extensions"]["MOZ_lightmap"];
      if (!ext.contains("extras") || !ext["extras"].contains("afterglow")) continue;
      const json& ag = ext["extras"]["afterglow"];
      const int atlas = ag.value("atlas", -1);
      if (atlas < 0 || atlas > 65535) continue;
      if (files.size() <= size_t(atlas)) files.resize(size_t(atlas) + 1);
      files[size_t(atlas)] = ag.value("exr", std::string());
    }
  }
  if (files.empty())
    return Status::error(gltfPath + ": no baked lightmaps (MOZ_lightmap) in this glTF; run "
                         "afterglow bake first");
  const fs::path dir = fs::path(gltfPath).parent_path();
  std::vector<LightmapImage> images;
  for (const std::string& f : files) {
    if (f.empty()) {
      images.emplace_back();
      continue;
    }
    Result<LightmapImage> img = readExr((dir / f).string());
    if (!img) return img.status();
    images.push_back(std::move(img.value()));
  }
  return images;
}

Result<std::vector<glm::vec3>> renderBaked(const scenes::Scene& scene, const RayTracer& tracer,
                                           const std::vector<LightmapImage>& lightmaps,
                                           const View& view, const RenderOptions& options,
                                           Progress& progress) {
  const int w = options.width, h = options.height;
  if (w <= 0 || h <= 0) return Status::error("render: the image size must be positive");
  const int spa = std::max(1, options.samplesPerAxis);
  const glm::vec3 right = glm::normalize(glm::cross(view.forward, view.up));
  const float tanHalf = std::tan(view.yfov * 0.5f);
  const float aspect = float(w) / float(h);
  std::vector<glm::vec3> image(size_t(w) * size_t(h), glm::vec3(0.0f));
  progress.begin("render", size_t(h));
  parallelFor(size_t(h), [&](size_t row) {
    if (progress.cancelled()) return;
    const int py = int(row);
    for (int px = 0; px < w; ++px) {
      glm::vec3 sum(0.0f);
      for (int sy = 0; sy < spa; ++sy) {
        for (int sx = 0; sx < spa; ++sx) {
          const float fx = (float(px) + (float(sx) + 0.5f) / float(spa)) / float(w);
          const float fy = (float(py) + (float(sy) + 0.5f) / float(spa)) / float(h);
          const float cx = (2.0f * fx - 1.0f) * tanHalf * aspect;
          const float cy = (1.0f - 2.0f * fy) * tanHalf;
          Ray ray;
          ray.origin = view.position;
          ray.direction = glm::normalize(view.forward + cx * right + cy * view.up);
          const Hit hit = tracer.intersect(ray);
          if (!hit.valid()) continue;
          const scenes::Instance& inst = scene.instances[hit.instance];
          const int material = scene.meshes[size_t(inst.mesh)].primitives[hit.primitive].material;
          const scenes::Material& mat = scene.material(material);
          const bool visibleSide = hit.frontFace || mat.doubleSided;
          if (!visibleSide) continue;
          const glm::vec2 uv0 = tracer.uv(hit, 0);
          glm::vec3 light(0.0f);
          const int atlas = inst.lightmap.atlas;
          if (atlas >= 0 && size_t(atlas) < lightmaps.size() && lightmaps[size_t(atlas)].width > 0)
            light = fetch(lightmaps[size_t(atlas)], tracer.uv(hit, 1));
          sum += diffuseAlbedo(scene, material, uv0) * light;
          if (hit.frontFace) sum += emittedRadiance(scene, material, uv0);
        }
      }
      image[size_t(py) * size_t(w) + size_t(px)] = sum / float(spa * spa);
    }
    progress.advance();
  }, 1);
  progress.end();
  if (progress.cancelled()) return Status::error("cancelled");
  return image;
}

Status writeRenderPng(const std::string& path, int width, int height,
                      const std::vector<glm::vec3>& image, float exposureStops) {
  const float exposure =
      std::isnan(exposureStops) ? autoExposure(image) : std::exp2(exposureStops);
  AtomicOutput out;
  if (Status s = writeTonemappedPng(path, width, height, image, exposure, out); !s) return s;
  return out.commit();
}

}  // namespace afterglow::baker
