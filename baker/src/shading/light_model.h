// How a KHR_lights_punctual light lights a point, shared by the precompute and the reference
// path tracer: unshadowed E/π for unit colour and intensity, and shadow rays toward the light's
// extent (the sun's disk for directional lights, the silhouette disk of a sphere of `radius`
// for point and spot lights), which is what makes soft shadows.
#pragma once

#include <algorithm>
#include <cmath>
#include <limits>

#include <glm/glm.hpp>

#include "afterglow/scenes/scene.h"
#include "shading/sampling.h"

namespace afterglow::baker {

// Shadow rays stop this fraction short of a light or emitter sample so the emitter itself, or
// geometry the light sits on, does not count as a blocker.
constexpr float kShadowShorten = 1e-3f;

// glTF's recommended range window (KHR_lights_punctual README).
inline float rangeWindow(float distance, float range) {
  if (range <= 0.0f) return 1.0f;
  const float x = distance / range;
  const float w = std::clamp(1.0f - x * x * x * x, 0.0f, 1.0f);
  return w * w;
}

// glTF's spot cone attenuation for the unit direction from the light to the receiver.
inline float spotCone(const scenes::Light& light, glm::vec3 toReceiver) {
  const float cosOuter = std::cos(light.outerConeAngle);
  const float cosInner = std::cos(light.innerConeAngle);
  const float scale = 1.0f / std::max(1e-3f, cosInner - cosOuter);
  const float offset = -cosOuter * scale;
  const float cd = glm::dot(glm::normalize(light.direction), toReceiver);
  const float a = std::clamp(cd * scale + offset, 0.0f, 1.0f);
  return a * a;
}

// The light as seen from one receiver point.
struct LightView {
  float transfer = 0.0f;        // unshadowed E/π for colour 1 and intensity 1; 0 = unlit
  glm::vec3 toCentre{0.0f};     // unit direction to the light's centre
  float distance = std::numeric_limits<float>::infinity();  // to the centre; ∞ for the sun
  bool hasExtent = false;       // a disk to spread shadow rays over
};

inline LightView viewLight(const scenes::Light& light, glm::vec3 p, glm::vec3 n) {
  LightView v;
  if (light.type == scenes::LightType::Directional) {
    v.toCentre = -glm::normalize(light.direction);
    const float cosTheta = glm::dot(n, v.toCentre);
    if (cosTheta > 0.0f) v.transfer = cosTheta / kPi;
    v.hasExtent = light.angularDiameter > 0.0f;
    return v;
  }
  const glm::vec3 d = light.position - p;
  const float dist = glm::length(d);
  if (!(dist > 0.0f)) return v;
  v.toCentre = d / dist;
  v.distance = dist;
  const float cosTheta = glm::dot(n, v.toCentre);
  if (cosTheta <= 0.0f) return v;
  float falloff = rangeWindow(dist, light.range) / (dist * dist);
  if (light.type == scenes::LightType::Spot) falloff *= spotCone(light, -v.toCentre);
  v.transfer = std::max(0.0f, cosTheta / kPi * falloff);
  v.hasExtent = light.radius > 0.0f;
  return v;
}

// A shadow ray's unit direction and length toward the point of the light's extent that u in
// [0,1)² picks (uniform over the sun's cone, or over the sphere's silhouette disk). Without an
// extent, the centre.
inline void lightShadowRay(const scenes::Light& light, const LightView& v, glm::vec3 p,
                           glm::vec2 u, glm::vec3* direction, float* length) {
  if (!v.hasExtent) {
    *direction = v.toCentre;
    *length = v.distance * (1.0f - kShadowShorten);
    return;
  }
  if (light.type == scenes::LightType::Directional) {
    const sampling::Frame frame(v.toCentre);
    *direction = frame.toWorld(sampling::uniformCone(u, std::cos(0.5f * light.angularDiameter)));
    *length = std::numeric_limits<float>::infinity();
    return;
  }
  const sampling::Frame frame(-v.toCentre);
  const glm::vec2 disk = sampling::uniformDisk(u);
  const glm::vec3 q = light.position + light.radius * (frame.t * disk.x + frame.b * disk.y);
  const glm::vec3 w = q - p;
  const float len = glm::length(w);
  *direction = len > 0.0f ? w / len : v.toCentre;
  *length = len * (1.0f - kShadowShorten);
}

}  // namespace afterglow::baker
