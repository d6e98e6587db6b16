// Cubemaps of RGB radiance for reflection probes (GLM only: engines sample probes with it).
//
// Layout. Six square faces of `size` × `size` texels, face-major, each face's rows top to
// bottom and each row left to right: texel (face, x, y) is texels[(face·size + y)·size + x].
// This is an OpenEXR cube environment map (header attribute envmap = ENVMAP_CUBE) read as one
// image `size` wide and 6·size high, the faces stacked vertically in OpenEXR's order:
//   0 +X   1 −X   2 +Y   3 −Y   4 +Z   5 −Z
// so the bake can write a probe as it is and oiiotool / maketx read it as a cube envmap.
//
// Axes. The project's world axes (glTF: right-handed, +Y up, +Z toward the viewer), which are
// the axes OpenEXR's convention is stated in; no axis is flipped on the way to the file.
//
// Orientation. With u, v ∈ [0, 1] across a face (u left → right, v top → bottom, the image's
// own directions) and a = 2u − 1, b = 2v − 1, the unnormalised direction is
//   face   direction        right (+u)   up (−v)   centre
//   +X     ( 1, −b,  a)     +Z           +Y        (1, 0, 0)
//   −X     (−1, −b, −a)     −Z           +Y        (−1, 0, 0)
//   +Y     ( a,  1, −b)     +X           +Z        (0, 1, 0)
//   −Y     ( a, −1,  b)     +X           −Z        (0, −1, 0)
//   +Z     (−a, −b,  1)     −X           +Y        (0, 0, 1)
//   −Z     ( a, −b, −1)     +X           +Y        (0, 0, −1)
// which is OpenEXR's ImfEnvmap.h (CubeMap::direction composed with the inverse of
// CubeMap::pixelPosition, whose pixel y runs down the image): every face is seen from inside
// the cube, e.g. looking along +X with +Y up, +Z is on the right. This is *not* the OpenGL /
// Vulkan cube-texture table (whose faces are seen from outside, a left-handed frame), but it
// is that table with z negated: upload the six faces unchanged with faces 4 and 5 swapped
// (ours −Z as the GPU's +Z and ours +Z as its −Z) and look up with (x, y, −z).
//
// Texel geometry. A texel is the square it covers: texel x spans u ∈ [x/size, (x+1)/size] and
// its centre is u = (x + 0.5)/size, so the 6·size² texels tile the sphere exactly (their solid
// angles sum to 4π). OpenEXR's CubeMap::direction instead puts the *centres* of a face's first
// and last pixels on the cube's edges (pos = pif/(size−1)·2 − 1); we do not, because then the
// edge texels of neighbouring faces overlap and no partition of the sphere (needed for the
// solid-angle weights of the prefilter) exists. The two differ by at most half a texel, at the
// face edges; face order and orientation are OpenEXR's exactly.
//
// Face selection. A direction belongs to the face of its largest absolute component, ties
// going to X before Y before Z (OpenEXR's faceAndPixelPosition).
#pragma once

#include <cstdint>
#include <vector>

#include <glm/glm.hpp>

namespace afterglow::runtime {

constexpr int kCubeFaceCount = 6;

// Face indices, in OpenEXR's order.
enum CubeFace : int {
  kCubeFacePosX = 0,
  kCubeFaceNegX = 1,
  kCubeFacePosY = 2,
  kCubeFaceNegY = 3,
  kCubeFacePosZ = 4,
  kCubeFaceNegZ = 5,
};

// RGB radiance texels (linear, the lightmaps' units), layout above.
struct Cubemap {
  int size = 0;                     // texels along a face's edge
  std::vector<glm::vec3> texels;    // kCubeFaceCount · size · size

  glm::vec3& at(int face, int x, int y) { return texels[size_t((face * size + y) * size + x)]; }
  const glm::vec3& at(int face, int x, int y) const {
    return texels[size_t((face * size + y) * size + x)];
  }
};

// A cubemap of `size` with every texel `value`.
Cubemap makeCubemap(int size, glm::vec3 value = glm::vec3(0.0f));

// One texel's address.
struct CubeTexel {
  int face = 0;
  int x = 0;   // column, left to right
  int y = 0;   // row, top to bottom
};

// A direction's place on the cube: its face and u, v ∈ [0, 1] across it (orientation above).
struct CubeFaceUv {
  int face = 0;
  float u = 0.0f;
  float v = 0.0f;
};

// The unit direction through (u, v) of a face (the table above). u, v outside [0, 1] extend
// the face's plane, which is what bilinear filtering across an edge uses.
glm::vec3 cubemapDirection(int face, float u, float v);

// The unit direction through the centre of texel (x, y) of a face of `size`.
glm::vec3 cubemapTexelDirection(int face, int x, int y, int size);

// The face and u, v a direction (any length > 0) falls on.
CubeFaceUv cubemapFaceUv(glm::vec3 dir);

// The texel a direction falls in (clamped to the face, so u = 1 lands in the last column).
CubeTexel cubemapTexel(glm::vec3 dir, int size);

// The solid angle (steradians) texel (x, y) subtends; the same on every face. Exact: the
// integral of the area element dA / (1 + s² + t²)^{3/2} over the texel's square on the unit
// face plane, whose antiderivative is atan(s·t / √(1 + s² + t²)).
float cubemapTexelSolidAngle(int x, int y, int size);

// Bilinear radiance in direction dir (any length > 0) between the four texel centres around
// it on dir's face. Within half a texel of a face edge, the centres beyond the edge (on the
// extended face plane) are read from the neighbouring face, bilinearly, where they project to,
// so filtering is seamless across edges (second-order accurate, like the face interiors); at a
// cube corner, where only three faces meet, the missing fourth value comes from one of the
// neighbours' edge texels.
glm::vec3 sampleCubemap(const Cubemap& cube, glm::vec3 dir);

// A cubemap with a one-texel border around each face holding what sampleCubemap reads beyond
// that face's edge (the neighbouring faces' values as it interpolates them), so a bilinear
// lookup never branches: sampleBorderedCubemap(withBorder(c), d) == sampleCubemap(c, d) bit for
// bit, several times faster on small faces (a rough mip's 2² faces are all edge). `size` stays
// the face's own; texels holds 6 · (size + 2)² values.
struct BorderedCubemap {
  int size = 0;
  std::vector<glm::vec3> texels;
};
BorderedCubemap withBorder(const Cubemap& cube);
glm::vec3 sampleBorderedCubemap(const BorderedCubemap& cube, glm::vec3 dir);
// The same at a direction's face and u, v (cubemapFaceUv), for lookups of one direction on
// several mips.
glm::vec3 sampleBorderedCubemap(const BorderedCubemap& cube, const CubeFaceUv& p);

// Where sampleBorderedCubemap reads on a bordered cube of face `size`: the top-left texel of
// its 2 × 2 square (texels[index], [index + 1], [index + m], [index + m + 1], m = size + 2)
// and the weights between them. Lookups whose direction is known ahead (the reflection
// capture's) keep this and skip the address arithmetic.
struct BorderedBilinear {
  uint32_t index = 0;
  float wx = 0.0f, wy = 0.0f;
};
BorderedBilinear borderedBilinear(int size, const CubeFaceUv& p);
inline glm::vec3 sampleBordered(const BorderedCubemap& cube, const BorderedBilinear& b) {
  const size_t m = size_t(cube.size) + 2;
  const glm::vec3* row = cube.texels.data() + b.index;
  const glm::vec3 top = glm::mix(row[0], row[1], b.wx);
  const glm::vec3 bottom = glm::mix(row[m], row[m + 1], b.wx);
  return glm::mix(top, bottom, b.wy);
}

// One texel's share of a filtered lookup: texels[index] (the layout above) times weight.
struct CubemapTap {
  uint32_t index = 0;
  float weight = 0.0f;
};
// At most this many taps per lookup: four texel centres, each beyond the face a bilinear
// read of the neighbouring face.
constexpr int kMaxCubemapTaps = 16;

// sampleCubemap as a linear operator: the texels it blends for dir on a cube of `size` and
// their weights (≥ 0, summing to 1; an index may repeat), so that sampleCubemap(cube, dir) =
// Σ taps[i].weight · cube.texels[taps[i].index]. Writes up to kMaxCubemapTaps taps and returns
// how many; 0 for size ≤ 0. (The prefilter's plan records these once instead of sampling.)
int cubemapBilinearTaps(int size, glm::vec3 dir, CubemapTap* taps);

}  // namespace afterglow::runtime
