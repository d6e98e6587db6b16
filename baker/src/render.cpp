#include "afterglow/baker/render.h"

#include <algorithm>
#include <cmath>
#include <filesystem>

#include <OpenImageIO/imageio.h>
#include <nlohmann/json.hpp>

#include "afterglow/baker/raytracer.h"
#include "afterglow/core/atomic_file.h"
#include "afterglow/core/parallel.h"
#include "afterglow/baker/bake_output.h"
#include "afterglow/baker/reflection_exr.h"
#include "afterglow/runtime/solver.h"
#include "afterglow/scenes/material_eval.h"
#include "path_tracer.h"
#include "sampling.h"
#include "sky_image.h"

namespace fs = std::filesystem;
using nlohmann::json;

namespace afterglow::baker {

namespace {

// Bilinear between texel centres, clamped at the edges (the bake dilated into the padding):
// as the reflection probes' capture reads them.
glm::vec3 fetch(const LightmapImage& lm, glm::vec2 uv) {
  return runtime::sampleClampedBilinear(lm.pixels, lm.width, lm.height, uv);
}

// Primary rays of a pinhole view, shared by both renders so that the baked and the reference
// picture see exactly the same geometry through the same pixels.
class PinholeCamera {
 public:
  PinholeCamera(const View& view, int width, int height)
      : view_(view),
        right_(glm::normalize(glm::cross(view.forward, view.up))),
        tanHalf_(std::tan(view.yfov * 0.5f)),
        aspect_(float(width) / float(height)),
        width_(float(width)),
        height_(float(height)) {}

  // The ray through picture point (x, y), in pixels from the top-left corner.
  Ray ray(float x, float y) const {
    const float cx = (2.0f * (x / width_) - 1.0f) * tanHalf_ * aspect_;
    const float cy = (1.0f - 2.0f * (y / height_)) * tanHalf_;
    Ray r;
    r.origin = view_.position;
    r.direction = glm::normalize(view_.forward + cx * right_ + cy * view_.up);
    return r;
  }

 private:
  View view_;
  glm::vec3 right_;
  float tanHalf_, aspect_, width_, height_;
};

// Fills a picture with shade(camera, px, py), row 0 at the top: rows in parallel (one row per
// task, so progress moves per row), stopping between pixels once progress is cancelled (a
// reference row at many samples per pixel takes a while).
template <class Shade>
Result<std::vector<glm::vec3>> renderPixels(const View& view, const RenderOptions& options,
                                            const char* stage, Progress& progress,
                                            const Shade& shade) {
  const int w = options.width, h = options.height;
  if (w <= 0 || h <= 0) return Status::error("render: the image size must be positive");
  const PinholeCamera camera(view, w, h);
  std::vector<glm::vec3> image(size_t(w) * size_t(h), glm::vec3(0.0f));
  progress.begin(stage, size_t(h));
  parallelFor(size_t(h), [&](size_t row) {
    for (int px = 0; px < w; ++px) {
      if (progress.cancelled()) return;
      image[row * size_t(w) + size_t(px)] = shade(camera, px, int(row));
    }
    progress.advance();
  }, 1);
  progress.end();
  if (progress.cancelled()) return Status::error("cancelled");
  return image;
}

// What the baked render shows at a primary ray's hit: diffuse albedo × lightmap + emission.
// Back faces of single-sided geometry and misses are black; surfaces without a lightmap
// (dynamic instances) show only their emission. With reflection probes, the diffuse colour and
// the probes' specular instead (render.h), as reflection_capture.h shades a probe's hits.
glm::vec3 bakedRadiance(const scenes::Scene& scene, const RayTracer& tracer,
                        const std::vector<LightmapImage>& lightmaps, const Ray& ray, const Hit& hit,
                        const runtime::ReflectionLighting* reflections) {
  if (!hit.valid()) return glm::vec3(0.0f);
  const scenes::Instance& inst = scene.instances[hit.instance];
  const int material = scene.meshes[size_t(inst.mesh)].primitives[hit.primitive].material;
  const scenes::Material& mat = scene.material(material);
  if (!hit.frontFace && !mat.doubleSided) return glm::vec3(0.0f);
  const glm::vec2 uv0 = tracer.uv(hit, 0);
  glm::vec3 light(0.0f);
  const int atlas = inst.lightmap.atlas;
  const bool lightmapped =
      atlas >= 0 && size_t(atlas) < lightmaps.size() && lightmaps[size_t(atlas)].width > 0;
  if (lightmapped) light = fetch(lightmaps[size_t(atlas)], tracer.uv(hit, 1));
  glm::vec3 radiance(0.0f);
  if (mat.emitsFrom(hit.frontFace)) radiance += emittedRadiance(scene, material, uv0);
  if (!reflections) return radiance + diffuseAlbedo(scene, material, uv0) * light;
  const scenes::SurfaceBrdf brdf = surfaceBrdf(scene, material, uv0);
  glm::vec3 normal = tracer.shadingNormal(hit);
  if (!hit.frontFace) normal = -normal;
  return radiance + brdf.diffuse * light +
         reflections->specular(ray.origin + hit.t * ray.direction, normal, -ray.direction,
                               brdf.f0, brdf.roughness, lightmapped ? &light : nullptr);
}

glm::vec3 jsonVec3(const json& v, bool* ok) {
  if (!v.is_array() || v.size() != 3 || !v[0].is_number() || !v[1].is_number() ||
      !v[2].is_number()) {
    *ok = false;
    return glm::vec3(0.0f);
  }
  return glm::vec3(v[0].get<float>(), v[1].get<float>(), v[2].get<float>());
}

// Copies report settings[key], a number (count 1) or an array of `count` numbers, into out;
// an absent key keeps the default (reports of older bakes). The error names the report.
Status readNumbers(const json& settings, const char* key, float* out, int count,
                   const std::string& report) {
  if (!settings.contains(key)) return Status::ok();
  const json& v = settings[key];
  const bool ok = count == 1 ? v.is_number()
                             : v.is_array() && v.size() == size_t(count) &&
                                   std::all_of(v.begin(), v.end(),
                                               [](const json& x) { return x.is_number(); });
  if (!ok)
    return Status::error(report + ": settings." + key +
                         (count == 1 ? " is not a number" : format(" is not %d numbers", count)));
  for (int i = 0; i < count; ++i) out[i] = (count == 1 ? v : v[size_t(i)]).get<float>();
  return Status::ok();
}

// A relative skyImage is relative to the folder the bake ran in, which the report does not
// record: use it as written when it exists from here (rendering from where one baked), else
// beside the report, where a moved output folder may have taken it along.
std::string resolveSkyImage(const std::string& recorded, const fs::path& reportDir) {
  const fs::path path(recorded);
  std::error_code ec;
  if (path.is_absolute() || fs::exists(path, ec)) return recorded;
  const fs::path beside = reportDir / path;
  return fs::exists(beside, ec) ? beside.string() : recorded;
}

}  // namespace

Result<LightmapImage> readLinearImage(const std::string& path) {
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

Ray cameraRay(const View& view, int width, int height, float x, float y) {
  return PinholeCamera(view, width, height).ray(x, y);
}

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
    Result<LightmapImage> img = readLinearImage((dir / f).string());
    if (!img) return img.status();
    images.push_back(std::move(img.value()));
  }
  return images;
}

Result<BakedReflections> loadBakedReflections(const std::string& gltfPath) {
  BakedReflections out;
  const fs::path dir = fs::path(gltfPath).parent_path() / "probes";
  const std::string path = (dir / "reflection_probes.json").string();
  std::error_code ec;
  if (!fs::is_regular_file(path, ec)) return out;
  Result<std::string> text = readFile(path);
  if (!text) return text.status();
  const json doc = json::parse(text.value(), nullptr, false);
  if (doc.is_discarded() || !doc.is_object() || !doc.contains("probes") ||
      !doc["probes"].is_array() || doc["probes"].empty())
    return Status::error(path + ": not a reflection probes file (no \"probes\" array)");
  const json& probes = doc["probes"];
  for (size_t i = 0; i < probes.size(); ++i) {
    const json& p = probes[i];
    const std::string what = path + ": probes[" + std::to_string(i) + "]";
    if (!p.is_object() || !p.contains("file") || !p["file"].is_string())
      return Status::error(what + " has no file");
    Result<std::vector<runtime::Cubemap>> chain = readCubemapExr((dir / p["file"].get<std::string>()).string());
    if (!chain) return Status::error(what + ": " + chain.message());
    out.chains.push_back(std::move(chain.value()));
    if (i == 0) continue;  // the sky: no box
    bool ok = p.contains("box") && p["box"].is_object() && p.contains("projectionBox") &&
              p["projectionBox"].is_object();
    runtime::ReflectionProbeBox b;
    if (ok) {
      const json& box = p["box"];
      b.centre = jsonVec3(box.value("centre", json()), &ok);
      b.halfSize = jsonVec3(box.value("halfSize", json()), &ok);
      const json axes = box.value("axes", json());
      if (!axes.is_array() || axes.size() != 3) ok = false;
      for (int a = 0; ok && a < 3; ++a) b.axes[a] = jsonVec3(axes[size_t(a)], &ok);
      b.projectionCentre = jsonVec3(p["projectionBox"].value("centre", json()), &ok);
      b.projectionHalfSize = jsonVec3(p["projectionBox"].value("halfSize", json()), &ok);
      b.capturePosition = jsonVec3(p.value("capturePosition", json()), &ok);
      const json blend = p.value("blendDistance", json()), importance = p.value("importance", json()),
                 projection = p.value("boxProjection", json());
      ok = ok && blend.is_number() && importance.is_number_integer() && projection.is_boolean();
      if (ok) {
        b.blendDistance = blend.get<float>();
        b.importance = importance.get<int>();
        b.boxProjection = projection.get<bool>();
      }
    }
    if (!ok)
      return Status::error(what + ": a box, projectionBox, capturePosition, blendDistance, "
                           "importance or boxProjection is missing or malformed");
    out.boxes.push_back(b);
  }
  const std::string dfgPath = (dir / "dfg.exr").string();
  Result<LightmapImage> dfg = readLinearImage(dfgPath);
  if (!dfg) return dfg.status();
  if (dfg->width != runtime::kDfgSize || dfg->height != runtime::kDfgSize)
    return Status::error(dfgPath + format(": %dx%d, the DFG table is %dx%d", dfg->width,
                                          dfg->height, runtime::kDfgSize, runtime::kDfgSize));
  for (const glm::vec3& v : dfg->pixels) out.dfg.emplace_back(v.x, v.y);
  for (const runtime::CubemapChain& c : out.chains) out.lights.push_back(runtime::probeLight(c));
  return out;
}

Result<std::vector<glm::vec3>> renderBaked(const scenes::Scene& scene, const RayTracer& tracer,
                                           const std::vector<LightmapImage>& lightmaps,
                                           const View& view, const RenderOptions& options,
                                           Progress& progress,
                                           const std::vector<ProbeSphere>& spheres,
                                           const BakedReflections* reflections) {
  const int spa = std::max(1, options.samplesPerAxis);
  const bool reflecting = reflections && !reflections->empty();
  const runtime::ReflectionLighting probes = reflecting ? reflections->lighting()
                                                        : runtime::ReflectionLighting();
  const runtime::ReflectionLighting* lighting = reflecting ? &probes : nullptr;
  ProbeSphereIndex sphereIndex(spheres, view, options.width, options.height);
  sphereIndex.setReflections(lighting);
  return renderPixels(view, options, "render", progress,
                      [&](const PinholeCamera& camera, int px, int py) {
    // A fixed grid: the picture of a bake has no noise of its own.
    glm::vec3 sum(0.0f);
    for (int sy = 0; sy < spa; ++sy)
      for (int sx = 0; sx < spa; ++sx) {
        const Ray ray = camera.ray(float(px) + (float(sx) + 0.5f) / float(spa),
                                   float(py) + (float(sy) + 0.5f) / float(spa));
        const Hit hit = tracer.intersect(ray);
        glm::vec3 sphere;
        if (!sphereIndex.empty() && sphereIndex.shade(ray, px, py, hit.t, &sphere))
          sum += sphere;
        else
          sum += bakedRadiance(scene, tracer, lightmaps, ray, hit, lighting);
      }
    return sum / float(spa * spa);
  });
}

Result<std::vector<glm::vec3>> renderReference(const scenes::Scene& scene,
                                               const RayTracer& tracer,
                                               const Environment& environment, const View& view,
                                               const RenderOptions& options, int samplesPerPixel,
                                               Progress& progress) {
  if (samplesPerPixel <= 0) return Status::error("render: samples per pixel must be positive");
  const PathTracer pathTracer(scene, tracer, environment, ReferenceOptions().maxDepth);
  const uint32_t spp = uint32_t(samplesPerPixel);
  return renderPixels(view, options, "reference render", progress,
                      [&](const PinholeCamera& camera, int px, int py) {
    const uint64_t pixel = uint64_t(py) * uint64_t(options.width) + uint64_t(px);
    glm::dvec3 sum(0.0);  // doubles: up to 2^20 samples of very different sizes
    for (uint32_t s = 0; s < spp; ++s) {
      // Seeded from (pixel, sample) alone, so no thread's schedule changes a path. The pixel
      // position is stratified; the first bounce direction is uniform, independent of it.
      sampling::Rng rng(sampling::Stream::ReferenceView, pixel, s);
      const glm::vec2 jitter = sampling::stratified2(rng, s, spp);
      const Ray ray = camera.ray(float(px) + jitter.x, float(py) + jitter.y);
      const glm::vec2 u = rng.next2();
      sum += glm::dvec3(pathTracer.cameraRadiance(ray, u, rng));
    }
    return glm::vec3(sum / double(spp));
  });
}

Result<Environment> loadBakeEnvironment(const std::string& gltfPath, bool* reportFound) {
  Environment env;  // a black sky, intensities 1: what a bake without options uses
  if (reportFound) *reportFound = false;
  std::error_code ec;
  // A built-in scene (builtin:...) is no file and has no report beside it.
  if (!fs::is_regular_file(gltfPath, ec)) return env;
  const fs::path reportPath = fs::path(gltfPath).parent_path() / "report.json";
  if (!fs::is_regular_file(reportPath, ec)) return env;
  const std::string report = reportPath.string();
  Result<std::string> text = readFile(report);
  if (!text) return text.status();
  const json doc = json::parse(text.value(), nullptr, false);
  if (doc.is_discarded() || !doc.is_object()) return Status::error(report + ": not valid JSON");
  const json settings = doc.value("settings", json::object());
  if (!settings.is_object()) return Status::error(report + ": \"settings\" is not an object");
  glm::vec3 sky(0.0f);
  if (Status s = readNumbers(settings, "indirectIntensity", &env.indirectIntensity, 1, report); !s)
    return s;
  if (Status s = readNumbers(settings, "albedoBoost", &env.albedoBoost, 1, report); !s) return s;
  if (Status s = readNumbers(settings, "sky", &sky[0], 3, report); !s) return s;
  const json image = settings.value("skyImage", json(""));
  if (!image.is_string())
    return Status::error(report + ": settings.skyImage is not a string");
  if (const std::string recorded = image.get<std::string>(); !recorded.empty()) {
    Status s = projectEquirectSky(resolveSkyImage(recorded, reportPath.parent_path()), env.skySh);
    if (!s) return Status::error(report + ": settings.skyImage: " + s.message());
  } else {
    runtime::constantSkySh(sky, env.skySh);
  }
  if (reportFound) *reportFound = true;
  return env;
}

Status writeRenderPng(const std::string& path, int width, int height,
                      const std::vector<glm::vec3>& image, float exposureStops) {
  const float exposure =
      std::isnan(exposureStops) ? autoExposure(image) : std::exp2(exposureStops);
  AtomicOutput out;
  if (Status s = writeTonemappedPng(path, width, height, image, exposure, out); !s) return s;
  return out.commit();
}

Status writeRenderExr(const std::string& path, int width, int height,
                      const std::vector<glm::vec3>& image) {
  AtomicOutput out;
  if (Status s = writeExr(path, width, height, image, out, ExrPixels::Float); !s) return s;
  return out.commit();
}

}  // namespace afterglow::baker
