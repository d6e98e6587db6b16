// Reflection probes' influence boxes: which probes light a point and by how much, and the
// parallax-corrected ("box projected") direction to look a probe's cubemap up with (GLM only:
// engines blend reflection probes with it).
//
// Conventions:
// - Units are metres, positions and directions are world space unless a name says local.
// - A box's local frame has its origin at the box's centre and its axes along the columns of
//   `axes` (an orthonormal matrix: the box may be turned); the box spans [−halfSize, +halfSize]
//   on each local axis.
// - Probe indices: probe 0 is the sky (the distant environment, no box; it takes whatever weight
//   the boxes leave), and boxes[i] is probe i + 1. A caller's cubemap array laid out the same
//   way (sky first, then the boxes in the order given) is indexed by ProbeWeight::probe directly.
//
// The weighting, per point p:
// 1. Every box holding p has a fade: its distance d from p to the nearest of its faces,
//    measured inward, over its blend distance b = min(blendDistance, smallest half-size),
//    through a smoothstep: t = clamp(d / b, 0, 1), fade = t²(3 − 2t). So the fade is 0 on the
//    faces and 1 from b inside them on; it is continuous with a continuous slope, at most
//    1.5 / b per metre. Clamping b to the smallest half-size lets a small box still reach 1 at
//    its centre. A blend distance ≤ 0 makes a hard edge (fade 1 everywhere inside: the weights
//    then jump where p crosses that box's faces, the one case without continuity).
// 2. Importance levels are taken from the highest down, starting with remaining = 1. A level
//    whose boxes have fades f_1..f_n covers C = 1 − Π(1 − f_k) of what remains, shared in
//    proportion to the fades: box k gets remaining · C · f_k / Σf. Then remaining *= 1 − C.
//    So where a more important box's fade is 1 the less important ones get exactly 0, and boxes
//    of one importance that overlap share (two fades of 1: a half each).
// 3. The sky gets what remains.
// The weights are ≥ 0, sum to 1 and are continuous in p (every term is a product of fades and of
// C · f_k / Σf, which is at most f_k and so goes to 0 with it). More: every partial derivative of
// a weight by a fade lies in [−1, 1], so a weight moves by at most Σ 1.5 / b_k per metre, summed
// over the boxes holding p.
//
// How this relates to Unity (from its manuals and, for HDRP's hierarchy weight, its shader
// source; read, not copied):
// - Built-in pipeline: a renderer (not a pixel) picks its probes; blending fades from one
//   probe's cubemap to the other's, so at most two probes (plus the skybox with "Blend Probes
//   And Skybox"), weighted by how much of the renderer's bounding box lies in each probe's box;
//   a probe of higher importance is used alone while the object is inside it and fades out as it
//   leaves. ReflectionProbe.blendDistance (default 1) is used by deferred shading, which blends
//   probes per pixel. Here the weights are per point, like deferred, any number of boxes blend,
//   and importance keeps Unity's meaning.
// - HDRP: each probe has an influence volume (box or sphere) and fades linearly within its
//   blend distance inward from the volume's border; the Advanced mode sets a blend distance per
//   face of a box (and a blend normal distance and face fades), and a Weight scales the probe's
//   whole contribution. Probes fill a hierarchy weight in the light loop's order: each adds its
//   weight clipped so that the total stays ≤ 1, and the sky takes the rest. Here the fade is a
//   smoothstep (no kink where it reaches 1), one blend distance serves all six faces, and boxes
//   of the same importance share symmetrically instead of by their order.
#pragma once

#include <vector>

#include <glm/glm.hpp>

namespace afterglow::runtime {

// One reflection probe's influence box, as authored on a glTF node (extras.afterglow.
// reflectionProbe). A box with a half-size that is not > 0 on every axis, or a value that is not
// finite, is ignored by reflectionProbesAt (weight 0) and not projected by boxProject.
struct ReflectionProbeBox {
  glm::vec3 centre{0.0f};           // the box's centre, world
  glm::mat3 axes{1.0f};             // columns: the box's local x, y, z axes in world, orthonormal
  glm::vec3 halfSize{1.0f};         // along the local axes, metres, > 0
  float blendDistance = 1.0f;       // metres inside the faces over which the weight fades in
  int importance = 1;               // higher wins where boxes overlap
  bool boxProjection = true;        // false: look the cubemap up with the reflected direction as is
  glm::vec3 capturePosition{0.0f};  // where the cubemap was captured, world (usually centre)
  // The box that box projection intersects (HDRP's "proxy volume"), on the same axes; a
  // projectionHalfSize that is not > 0 on every axis means the influence box itself. They differ
  // for a box fitted to a room: the projection box is the walls and the influence box reaches
  // blendDistance beyond them, so that the walls themselves (and what stands on them) get the
  // probe's full weight instead of the fade's 0 at the influence box's faces.
  glm::vec3 projectionCentre{0.0f};
  glm::vec3 projectionHalfSize{0.0f};
};

// The box of a probe on a node: `size` is the box's full edge lengths in the node's local units
// (a unit cube scaled by size; signs ignored), so the node's scale scales it too. The centre and capture
// position are the node's origin; the axes are the node's turned axes, orthonormalised (a
// shear, which a glTF hierarchy can produce with non-uniform scales, is dropped; a mirrored node
// gives a right-handed frame, the box being symmetric). A zero scale gives a zero half-size: the
// box is then ignored. blendDistance, importance and boxProjection keep their defaults.
ReflectionProbeBox reflectionProbeBoxFromNode(const glm::mat4& nodeToWorld, glm::vec3 size);

// The box's fade at p (step 1 above): 0 outside and on the faces, rising to 1 at the blend
// distance inside. 0 for a box that is ignored (see ReflectionProbeBox).
float reflectionProbeFade(const ReflectionProbeBox& box, glm::vec3 p);

struct ProbeWeight {
  int probe;     // 0: the sky; i + 1: boxes[i]
  float weight;  // > 0
};

// The probes lighting p and their weights (above), in increasing probe index, only the probes
// with a weight > 0: at least one entry, the weights summing to 1 (within 1e-6). Outside every
// box, or for a p that is not finite, the sky alone with weight 1. Computed in double precision;
// the cost is one box test per box (callers with many boxes cull them first, e.g. with a grid).
std::vector<ProbeWeight> reflectionProbesAt(const std::vector<ReflectionProbeBox>& boxes,
                                            glm::vec3 p);

// The direction to look the box's cubemap up with for a surface at `position` reflecting along
// `direction` (Lagarde and Zanuttini 2012, "Local image-based lighting with parallax-corrected
// cubemaps"): the ray leaves the box at a wall point, and the cubemap saw that point from the
// capture position, so the result is normalize(hit − capturePosition). The ray is intersected
// with the projection box (the influence box unless one is given) in the box's local frame
// (slabs), in double precision. A `position` outside the projection box (in an influence box's
// margin beyond the walls, or a hit a rounding error outside them) is first clamped onto it,
// which keeps the lookup continuous. Returns `direction` unchanged (not normalised) when
// box.boxProjection is false, when the box is ignored, when `direction` is zero or not finite,
// or when the hit is the capture position itself.
glm::vec3 boxProject(const ReflectionProbeBox& box, glm::vec3 position, glm::vec3 direction);

}  // namespace afterglow::runtime
