// The sky as an EXT_lights_image_based light in the output glTF, so a standard viewer
// (Babylon.js, the extension's reference loader) opens a baked level lit by the same sky.
// Library code: the bake calls attachImageBasedLight once reflection probes are wired in.
//
// What the extension holds (KhronosGroup/glTF extensions/2.0/Vendor/EXT_lights_image_based):
// a root `extensions.EXT_lights_image_based.lights[]`, each with `name`, `rotation` (a
// quaternion), `intensity`, `irradianceCoefficients` (9 × [r, g, b], SH l ≤ 2),
// `specularImageSize` (mip 0's edge, a power of two) and `specularImages` (per mip, 6 glTF
// image indices, faces +X −X +Y −Y +Z −Z); a scene points at one with
// `scenes[i].extensions.EXT_lights_image_based.light`. What follows is what Babylon.js's loader
// (loaders/src/glTF/2.0/Extensions/EXT_lights_image_based.ts) does with them, read from its
// source; the spec leaves axes, roughness and SH scaling unsaid.
//
// Images. Every face image is decoded as RGBD whatever its type (the loader always calls
// updateRGBDAsync; the spec's "3-channel PNG or JPEG = LDR" is not implemented), so each is a
// 4-channel PNG in Babylon's RGBD (helperFunctions toRGBD / fromRGBD):
//   D = clamp(floor(max(255 / max(r, g, b), 1)) / 255, 0, 1),  rgb' = (rgb · D)^(1/2.2),
//   stored (rgb', D) in 8 bits; decoded rgb = rgb'^2.2 / D.
// Radiances up to 255 survive (about 1% steps); brighter ones clip at 255. The alpha must be
// written unassociated (OpenImageIO otherwise divides the colour by it).
//
// Faces. The loader uploads each PNG flipped vertically (createTexture(invertY = true), then
// rendered into the cube face), and the PBR shader samples the cube with the world reflection
// vector in Babylon's left-handed frame, where the glTF loader's __root__ node (rotation 180°
// about Y, scale z −1) puts glTF's (x, y, z) at (−x, y, z). With GL's cube-face table for the
// faces, slot s of the extension shows, per pixel (column c, row r) of an N² image, our texel:
//   slot 0 (+X): our −X, (c, N−1−r)     slot 1 (−X): our +X, (c, N−1−r)
//   slot 2 (+Y): our +Y, (N−1−c, r)     slot 3 (−Y): our −Y, (N−1−c, r)
//   slot 4 (+Z): our +Z, (c, N−1−r)     slot 5 (−Z): our −Z, (c, N−1−r)
// (extLightsFaceTexel). That is Babylon's default (left-handed scene, the loader's AUTO mode).
// A right-handed Babylon scene (useRightHandedSystem) has no __root__ flip but negates z in
// the lookup (REFLECTIONMAP_OPPOSITEZ), which turns the sky 180° about +Y relative to the
// geometry; a `rotation` of [0, 1, 0, 0] undoes that for such a viewer.
//
// Irradiance. The loader takes irradianceCoefficients C, scales them by `intensity` (which
// must be present: an absent intensity makes every coefficient NaN in Babylon), divides by π
// (convertIrradianceToLambertianRadiance) and, with its default SH path, shades with
//   albedo × Σ_i (C_i / π) · Y^B_i(n_B),
// Y^B the real SH with the Condon–Shortley phase (the l1_1, l11, l2_1, l21 constants negative)
// and n_B the normal in its frame (−x, y, z). That is E(n)/π when C is the irradiance SH in
// that basis and frame, E_i = Â_l · L_i (Ramamoorthi & Hanrahan: Â = π, 2π/3, π/4), which is
// what the extension names them. Ours (runtime/probe_sh.h) is the radiance SH L_i = ∫ L Y_i dω
// in glTF's frame with every constant positive, so
//   C_i = Â_l · s_i · L_i,   s = (+, −, +, +, −, −, +, +, +)
// (the phase flips 1, 3, 5, 7; the frame's x → −x flips the x-odd 3, 4, 7). A constant sky of
// radiance L gives C_0 = π · 2√π · L and E/π = L, and nothing else.
//
// Roughness. Babylon picks the mip from α = roughness² as lod = log2(size · α) · (n − 1) /
// log2(size) for n mips of edge `size` (getLodFromAlphaG with the loader's
// lodGenerationScale), i.e. mip m holds α = size^(m/(n−1) − 1), r = √α
// (babylonRoughnessOfMip). The spec says the mips "evenly map to roughness 0 to 1"; our chain
// follows Unity (runtime/reflection_prefilter.h). For 7 mips of 128²: Babylon reads mips 0..6
// as r = 0.09 0.13 0.20 0.30 0.45 0.67 1, ours are r = 0 0.10 0.21 0.34 0.49 0.68 1: at most a
// tenth of roughness apart. Prefilter the sky's chain at babylonRoughnessOfMip for an exact
// match in Babylon.
#pragma once

#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include <glm/glm.hpp>
#include <nlohmann/json_fwd.hpp>

#include "afterglow/bakefiles/layout.h"
#include "afterglow/core/atomic_file.h"
#include "afterglow/core/status.h"
#include "afterglow/runtime/cubemap.h"
#include "afterglow/runtime/probe_sh.h"

namespace afterglow::bakefiles {

constexpr const char* kExtLightsImageBased = "EXT_lights_image_based";

// irradianceCoefficients for a sky whose radiance SH (our basis and axes) is `radianceSh`:
// C_i = Â_l · s_i · L_i, above.
std::array<glm::vec3, runtime::kShCount> extLightsIrradianceCoefficients(
    const runtime::ShL2& radianceSh);

// Babylon's RGBD (above): linear RGB (negative and NaN as 0) to 4 bytes, and back.
std::array<uint8_t, 4> encodeRgbd(glm::vec3 linear);
glm::vec3 decodeRgbd(const std::array<uint8_t, 4>& rgbd);

// The texel of ours (face, x, y) that pixel (column, row) of the extension's face `slot`
// (0..5: +X −X +Y −Y +Z −Z) of an N² mip shows in Babylon (the table above).
runtime::CubeTexel extLightsFaceTexel(int slot, int column, int row, int size);

// The perceptual roughness Babylon reads mip `mip` of `mipCount` mips of edge `size` as
// (above); 0 when mipCount ≤ 1.
float babylonRoughnessOfMip(int mip, int mipCount, int size);

struct ImageBasedLightOptions {
  std::string name = "sky";
  float intensity = 1.0f;
  std::string imageFolder = kProbesDir;      // beside the glTF, relative to outDir
  std::string imagePrefix = "sky_specular";  // <prefix>_m<mip>_f<slot>.png
};

// Writes outDir/<imageFolder>/<prefix>_m<m>_f<s>.png for every mip m and slot s through `out`
// (not committed), lists them in `doc`'s images, and adds a light to `doc` (a glTF document:
// the bake's output before it is written): the root extension's `lights` (appended when there
// already are some), `rotation` [0, 0, 0, 1], `intensity`, the coefficients above,
// `specularImageSize` = mips[0].size and `specularImages`; every scene's
// `extensions.EXT_lights_image_based.light`; and the name in `extensionsUsed` (not
// `extensionsRequired`: a viewer without it still shows the level). mips[m] must have edge
// mips[0].size >> m, mips[0].size a power of two (the extension's rule), every texel finite;
// the document must have a scene. Returns the written paths; on an error `doc` is unchanged.
Result<std::vector<std::string>> attachImageBasedLight(
    nlohmann::json& doc, const std::string& outDir, const runtime::ShL2& skyRadianceSh,
    const std::vector<runtime::Cubemap>& specularMips, AtomicOutput& out,
    const ImageBasedLightOptions& options = {});

// Removes every EXT_lights_image_based light named `name` from `doc`, so that attaching a new
// one replaces it (afterglow relight re-lights a bake's scene.gltf, which already holds the
// bake's sky, and would otherwise list two). Also removes the images only those lights used
// (renumbering the rest in textures' `source`, their extensions' `source` and the remaining
// lights' specularImages), the scenes' pointers to them (others renumbered) and, when no light
// is left, the extension and its extensionsUsed entry. Returns how many lights were removed; a
// document without the extension is left as it is.
size_t detachImageBasedLights(nlohmann::json& doc, const std::string& name);

}  // namespace afterglow::bakefiles
