// Seam stitching. The unwrapper cuts surfaces into charts; along a cut (a seam) one mesh edge
// appears twice in the atlas, once per chart, and the texels on either side are baked
// independently, so a renderer filtering the lightmap bilinearly sees a visible step where the
// surface itself runs on smoothly (a cylinder's cut, a large plane split in two). Stitching
// makes the bilinear lookups on both sides of each seam agree, as linear mixes of texel values
// (lightmap_post.h), in the spirit of Sloan's "Stitch Lightmap Seams" (The Witness).
//
// Which seams: edges of one lightmapped static instance whose two triangles share both world
// endpoints (welded within 1e-5 of the instance's bounding-box diagonal) but not their uv1, and
// whose face normals and shading normals at both endpoints differ by at most
// PostOptions::stitchMaxAngleDeg (30°). A box's 90° corner is a chart boundary where the two
// faces are legitimately lit differently, so it is never stitched; neither are edges between
// instances (separate objects) nor non-manifold edges (three or more triangles).
//
// How: each seam is sampled every half texel (in the longer of its two sides, in pixels). At
// sample s, side A's bilinear footprint a_s and side B's b_s are 4 pixel weights each; with
// d_s = a_s − b_s and x0 the pixels' unstitched values (after fill and dilation, so footprints
// reaching into the padding read dilated pixels), the stitched pixels x minimise
//   Σ_s (d_s·x)² + λ Σ_p (x_p − x0_p)²
// over the pixels any footprint touches. Every d_s sums to zero, so a constant lightmap is a
// fixed point and weights keep summing to one. It is solved by 8 Gauss-Seidel sweeps over the
// samples on the dual system (seams.cpp says why not over the pixels), carried out on mixes
// (each pixel a sparse weight vector over texels), so the result is again a mix per pixel, at
// most PostOptions::stitchMaxMix (16) entries, and linear in the texel values. λ = 0.05
// against |d_s|² ≈ 0.6 for a sample on a chart's edge: the seam term dominates, the anchor
// only picks, among the ways to make the sides agree, the one that changes the pixels least
// (the two sides meet in the middle and smooth light stays put), and keeps the dual well
// conditioned, so 8 sweeps reach the minimiser (16 change nothing more). Last, negative
// weights are dropped (seams.cpp: makeConvex) so no light goes negative. On a plane cut into
// two charts at different scale and orientation (tests/baker_seams_test.cpp) the step across
// the seam shrinks about 12-fold; pixels move by at most about two thirds of the step.
// Footprint pixels with no mix (unbaked padding, with dilation 0) stay black and are not
// solved for.
#pragma once

#include <cstdint>
#include <vector>

#include <glm/glm.hpp>

#include "post/lightmap_post.h"

namespace afterglow::baker {

// One seam edge in atlas pixel coordinates (uv1 × atlas size): side A runs a0 → a1 and side B
// b0 → b1, a0 and b0 being the same world point (as are a1 and b1).
struct Seam {
  glm::vec2 a0, a1;
  glm::vec2 b0, b1;
};

// The seams to stitch, per atlas (indexed like `atlases`), over the scene's lightmapped static
// instances, in instance and edge order. Deterministic whatever the thread count.
std::vector<std::vector<Seam>> findSeams(const scenes::Scene& scene,
                                         const std::vector<runtime::AtlasLayout>& atlases,
                                         float maxAngleDeg);

// Stitches one atlas's seams into `mix` (width × height pixel mixes; `has` marks the pixels
// that hold one; only those are stitched) and adds what it did to `stats`.
void stitchSeams(const std::vector<Seam>& seams, int width, int height,
                 const PostOptions& options, std::vector<PixelMix>& mix,
                 const std::vector<uint8_t>& has, PostStats& stats);

}  // namespace afterglow::baker
