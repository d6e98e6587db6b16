// The reflection probes' EXR files: a probe's prefiltered cubemap chain as one OpenEXR cube
// environment map with mip levels, and the split-sum DFG table. Library functions: the bake
// writes them into OUT/probes/ once reflection-probe capture is wired in (issue 15).
//
// Cube environment map (what oiiotool, exrenvmap and OpenEXR's ImfEnvmap read):
// - One tiled image `size` wide and 6·size high, the six faces stacked vertically in
//   runtime/cubemap.h's layout, which is OpenEXR's (+X −X +Y −Y +Z −Z, ImfEnvmap.h's
//   orientation), linear RGB. Header `envmap` = ENVMAP_CUBE, written by OpenImageIO from
//   `textureformat` = "CubeFace Environment" (oiiotool --info -v shows that string: it is how
//   OIIO reports the envmap attribute).
// - Texel geometry differs from OpenEXR's by at most half a texel at face edges: our texel is
//   the square it covers, CubeMap::direction puts the edge texels' centres on the cube's edges
//   (runtime/cubemap.h says why). Face order and orientation are OpenEXR's exactly.
// - Mip levels (MIPMAP_LEVELS, ROUND_DOWN, 64² tiles, like exrenvmap -m and OpenEXR's sample
//   StageEnvCube.exr). OpenEXR fixes the level count from the data window, not the writer:
//   floor(log2(6·size)) + 1 levels, level m being max(1, size >> m) × max(1, 6·size >> m), and a
//   reader fails on a level whose tiles are missing. So a 128² probe's file has 10 levels:
//   128×768 ... 2×12 (our 7 prefiltered mips), then 1×6, 1×3, 1×1. Levels 0 .. n−1 hold the n
//   mips given; each level after them is the 2×2 box average of the one before (1×6 is still a
//   cube, a further blur of the roughest mip; 1×3 and 1×1 are no cube at all, only there
//   because the format needs them). The header's int `afterglow:prefilteredLevels` = n says
//   where the prefiltered chain ends; readCubemapExr returns those levels only.
// - OpenImageIO's TextureSystem does not look up cube maps: environment() treats every
//   environment map as lat-long (OIIO 2.4's environment.cpp), and maketx builds lat-long maps
//   only. Engines and exrenvmap read the faces as above.
// - Half floats by default (as the lightmaps), values above half's largest finite value (65504)
//   clamped to it: an infinity would poison every filtered lookup that touches it. Float keeps
//   them.
//
// DFG table: size × size (64 × 64) 32-bit float RGB, R = scale, G = bias, B = 0 (the split sum's
// F0 · scale + bias, runtime/reflection_prefilter.h's dfgTable), row-major with row 0 the
// smoothest: pixel (x, y) is NdotV = (x + 0.5)/size, perceptual roughness = (y + 0.5)/size, the
// first row of the file at v = 0 (glTF's and OpenImageIO's image orientation). Three channels
// rather than two so any viewer shows it; an engine uploads R and G (UE's PreIntegratedGF,
// Filament's DFG LUT layout).
#pragma once

#include <string>
#include <vector>

#include <glm/glm.hpp>

#include "afterglow/bakefiles/images.h"
#include "afterglow/core/atomic_file.h"
#include "afterglow/core/status.h"
#include "afterglow/runtime/cubemap.h"

namespace afterglow::bakefiles {

// Writes the cube environment map above through `out` (not committed; missing folders are
// created, as for every bake output). mips[m] must be size >> m for size = mips[0].size, with
// size divisible by 2^(mips.size() − 1) so every mip is one of OpenEXR's cube levels; every
// texel finite. An error names the path (and the mip, face and texel at fault).
Status writeCubemapExr(const std::string& path, const std::vector<runtime::Cubemap>& mips,
                       AtomicOutput& out, ExrPixels pixelType = ExrPixels::Half);
// The same for a tool writing one file now: the path's folder must exist (an error naming the
// path otherwise), the file appears complete or not at all (a temporary beside it, renamed).
Status writeCubemapExr(const std::string& path, const std::vector<runtime::Cubemap>& mips,
                       ExrPixels pixelType = ExrPixels::Half);

// Reads a cube environment map written above, or any OpenEXR cube map (envmap = cube, size ×
// 6·size): its levels while they are cubes (width w, height 6w), as many as
// `afterglow:prefilteredLevels` says when the file has it. An error names the path and what is
// wrong (missing, not OpenEXR, not a cube map, a bad level).
Result<std::vector<runtime::Cubemap>> readCubemapExr(const std::string& path);

// Writes the DFG table (dfgTable(size)'s layout: table[row · size + column], (scale, bias))
// as the EXR above, through `out`. table.size() must be size², every value finite.
Status writeDfgExr(const std::string& path, const std::vector<glm::vec2>& table, int size,
                   AtomicOutput& out);
// The same now: the folder must exist; complete or nothing.
Status writeDfgExr(const std::string& path, const std::vector<glm::vec2>& table, int size);

}  // namespace afterglow::bakefiles
