// The bake folder's layout: every file `afterglow bake` and `afterglow relight` write into OUT/,
// named here once. Paths are relative to the folder, with '/' (as glTF URIs are).
//
//   scene.gltf, scene.bin           the level with TEXCOORD_1 and MOZ_lightmap materials
//   report.json                     counts, settings, stage times, warnings
//   transport.agt                   the transport, for the runtime and `afterglow relight`
//   lightmaps/lightmap<i>.exr       linear half-float E/π per atlas
//   lightmaps/lightmap<i>.png       its tone-mapped preview
//   lightmaps/lightmap<i>_d{x,y,z}.exr  directional: the bounced light's gradient per axis
//                                   (indirect<i>_d*.exr with two resolutions)
//   probes/light_probes.json        light probes: positions, kinds, tetrahedra, settings
//   probes/light_probes_sh.bin      their radiance SH L2
//   probes/reflection_probes.json   reflection probes: boxes, files, mips
//   probes/reflection_sky.exr       the sky's cube map, then reflection_<i>.exr per probe
//   probes/dfg.exr                  the split sum's DFG table
//   probes/sky_specular_*.png       the sky for EXT_lights_image_based viewers
#pragma once

#include <string>

namespace afterglow::bakefiles {

constexpr const char kSceneGltf[] = "scene.gltf";
constexpr const char kSceneBin[] = "scene.bin";
constexpr const char kReport[] = "report.json";
constexpr const char kTransport[] = "transport.agt";
constexpr const char kLightmapsDir[] = "lightmaps";
constexpr const char kProbesDir[] = "probes";
// Within kProbesDir (light_probes.json names its SH file relative to itself).
constexpr const char kLightProbesJson[] = "light_probes.json";
constexpr const char kLightProbesSh[] = "light_probes_sh.bin";
// Mixed lights' probe occlusion (Unity's), when a light is mixed.
constexpr const char kLightProbeOcclusion[] = "light_probe_occlusion.json";
constexpr const char kReflectionProbesJson[] = "reflection_probes.json";
constexpr const char kDfgExr[] = "dfg.exr";

// "lightmaps/lightmap<atlas>.exr" and ".png".
std::string lightmapExr(size_t atlas);
std::string lightmapPng(size_t atlas);
// Two resolutions: the indirect grid's atlases (its sky and bounced light, E/π), which an engine
// reads at TEXCOORD_2 and composes with the direct light.
std::string indirectExr(size_t atlas);
std::string indirectPng(size_t atlas);
// Directional lightmaps: the bounced light's gradient along world axis `axis` (0 x, 1 y, 2 z)
// for the transport's atlas `atlas`: "lightmaps/lightmap<atlas>_dx.exr" (..._dy, _dz), or with
// two resolutions (`grid`) "lightmaps/indirect<atlas>_dx.exr", read at the grid's TEXCOORD_2.
std::string directionalExr(size_t atlas, int axis, bool grid);
// Mixed lights' shadowmask for lightmap atlas `atlas`: RGBA, linear 8-bit visible fractions.
std::string shadowmaskPng(size_t atlas);
// A reflection chain's cube map within kProbesDir: "reflection_sky.exr" for chain 0 (the sky),
// "reflection_<i>.exr" for probe i's.
std::string reflectionExr(size_t chain);

// `file` (relative to the folder) in bake folder `dir`, as a path to open.
std::string inFolder(const std::string& dir, const std::string& file);
// A file of kProbesDir in bake folder `dir`.
std::string inProbes(const std::string& dir, const std::string& file);

}  // namespace afterglow::bakefiles
