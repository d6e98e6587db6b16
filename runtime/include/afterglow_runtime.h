/* The afterglow relighting runtime as a plain C API (C99), for engines and languages that cannot
 * use the C++ class afterglow::runtime::Runtime (afterglow/runtime/runtime.h). Same semantics,
 * same threading rules; see that header for the details.
 *
 *   char err[256];
 *   AfterglowRuntime* rt = afterglow_runtime_load("out/transport.agt", err, sizeof err);
 *   if (!rt) { puts(err); return; }
 *   int sun = afterglow_runtime_find_light(rt, "Sun");
 *   AfterglowUpdateOptions opt;
 *   afterglow_runtime_default_options(&opt);
 *   opt.max_bounces = 1;
 *   ... each frame:
 *   afterglow_runtime_set_light_color(rt, sun, 1.0f, 0.8f, 0.6f);
 *   afterglow_runtime_update(rt, &opt, NULL);
 *   afterglow_runtime_read_atlas(rt, 0, pixels, pixelFloatCount);
 *   ...
 *   afterglow_runtime_free(rt);
 *
 * Indices: lights 0..light_count-1, materials 0..material_count-1, atlases 0..atlas_count-1.
 * Functions returning int as a result return 1 on success and 0 on failure (invalid handle or
 * index, non-finite value, buffer too small); nothing here aborts or throws across the API.
 * Threads: setters, getters and the reads (read_atlas, read_texels, probe_sh, read_cubemap, ...)
 * may run concurrently with each other and with the updates (reads see one whole completed
 * update); afterglow_runtime_update, _update_probes and _update_reflection_probes are serialised.
 */
#ifndef AFTERGLOW_RUNTIME_H
#define AFTERGLOW_RUNTIME_H

#include <stddef.h>

#ifdef __cplusplus
extern "C" {
#endif

typedef struct AfterglowRuntime AfterglowRuntime; /* opaque */

typedef struct AfterglowUpdateOptions {
  int max_bounces;       /* > 0: exactly this many; 0: until converged (or 1000); < 0: none */
  float tolerance;       /* largest relative change that counts as converged (default 1e-3) */
  double time_budget_ms; /* > 0: stop starting passes that would overrun (first pass runs) */
  int from_scratch;      /* nonzero: reset bounced light first (matches a fresh bake) */
  int probes;            /* nonzero (default): refresh the light probes after the lightmaps */
  /* Reflection probe capture passes ("units": one pass of one probe) after the light probes:
   * < 0 a full round from the first unit (default: reproduces the bake), 0 none (the cubemaps
   * keep their last values), n at most n, carrying on where the last call stopped. Appended
   * after the light probes' field, as every addition to these structs is: fill them with
   * afterglow_runtime_default_options, never by hand. */
  int reflection_passes;
} AfterglowUpdateOptions;

typedef struct AfterglowUpdateStats {
  int bounces;         /* passes run */
  int converged;       /* 1 when the last pass changed less than the tolerance */
  float change;        /* the last pass's largest relative change (0 when none ran) */
  double milliseconds; /* wall time of the call */
  int probes;                /* light probes refreshed */
  double probe_milliseconds; /* of which the probes took */
  int reflection_passes;          /* reflection probe capture passes run */
  double reflection_milliseconds; /* of which the reflection probes took */
} AfterglowUpdateStats;

/* The defaults: max_bounces 0, tolerance 1e-3, no budget, warm start, light probes refreshed, a
 * full round of reflection probe passes. */
void afterglow_runtime_default_options(AfterglowUpdateOptions* options);

/* Loads a transport file. On failure returns NULL and writes a one-line, NUL-terminated message
 * starting with the path into err (truncated to err_size; err may be NULL). */
AfterglowRuntime* afterglow_runtime_load(const char* path, char* err, size_t err_size);
void afterglow_runtime_free(AfterglowRuntime* runtime); /* NULL is fine */

/* Lights (punctual sources). Names stay valid until afterglow_runtime_free; NULL when invalid. */
int afterglow_runtime_light_count(const AfterglowRuntime* runtime);
const char* afterglow_runtime_light_name(const AfterglowRuntime* runtime, int light);
int afterglow_runtime_find_light(const AfterglowRuntime* runtime, const char* name); /* or -1 */
int afterglow_runtime_set_light_color(AfterglowRuntime* runtime, int light, float r, float g,
                                      float b);
int afterglow_runtime_set_light_intensity(AfterglowRuntime* runtime, int light, float intensity);
int afterglow_runtime_set_bounce_intensity(AfterglowRuntime* runtime, int light, float scale);
int afterglow_runtime_set_light_enabled(AfterglowRuntime* runtime, int light, int enabled);

/* Sky: a constant radiance, or SH L2 as 9 RGB coefficients (27 floats, coefficient-major). */
int afterglow_runtime_set_sky(AfterglowRuntime* runtime, float r, float g, float b);
int afterglow_runtime_set_sky_sh(AfterglowRuntime* runtime, const float* sh27);

/* Materials. set_emission fails for materials that were not emissive at bake time
 * (afterglow_runtime_can_set_emission says which). */
int afterglow_runtime_material_count(const AfterglowRuntime* runtime);
const char* afterglow_runtime_material_name(const AfterglowRuntime* runtime, int material);
int afterglow_runtime_find_material(const AfterglowRuntime* runtime, const char* name);
int afterglow_runtime_set_albedo(AfterglowRuntime* runtime, int material, float r, float g,
                                 float b);
int afterglow_runtime_set_emission(AfterglowRuntime* runtime, int material, float r, float g,
                                   float b);
int afterglow_runtime_can_set_emission(const AfterglowRuntime* runtime, int material);

int afterglow_runtime_set_indirect_intensity(AfterglowRuntime* runtime, float scale);

/* Applies the pending settings and runs bounce passes. options NULL: the defaults; stats may be
 * NULL. Returns 0 for a NULL handle, or when memory ran out (the reflection probes' passes
 * allocate their cubemaps, which then keep their last published values). */
int afterglow_runtime_update(AfterglowRuntime* runtime, const AfterglowUpdateOptions* options,
                             AfterglowUpdateStats* stats);

/* Atlases from the last completed update: linear RGB floats, width*height*3, row 0 at v = 0.
 * read_atlas fails when float_count is below width*height*3. */
int afterglow_runtime_atlas_count(const AfterglowRuntime* runtime);
int afterglow_runtime_atlas_width(const AfterglowRuntime* runtime, int atlas);
int afterglow_runtime_atlas_height(const AfterglowRuntime* runtime, int atlas);
int afterglow_runtime_read_atlas(const AfterglowRuntime* runtime, int atlas, float* rgb,
                                 size_t float_count);

/* Per-texel values (texel_count*3 floats). */
int afterglow_runtime_texel_count(const AfterglowRuntime* runtime);
int afterglow_runtime_read_texels(const AfterglowRuntime* runtime, float* rgb, size_t float_count);

/* Light probes: radiance SH L2 per probe, 27 floats (9 coefficients × RGB, coefficient-major:
 * c0.r c0.g c0.b c1.r ...), in the order and normalisation of runtime/probe_sh.h. Reads see the
 * last published probe update. Functions returning int return 0 for a NULL handle or an invalid
 * index. */
int afterglow_runtime_probe_count(const AfterglowRuntime* runtime);
int afterglow_runtime_probe_position(const AfterglowRuntime* runtime, int probe, float* xyz);
int afterglow_runtime_probe_sh(const AfterglowRuntime* runtime, int probe, float* sh27);
/* Tetrahedral interpolation at (x, y, z), weighed by the probes' visibility of the point (no light
 * through walls); *hint (may be NULL) starts the walk and receives the
 * tetrahedron found. */
int afterglow_runtime_sample_probes(const AfterglowRuntime* runtime, float x, float y, float z,
                                    int* hint, float* sh27);
/* E/π (rgb) for a unit normal from 27 SH floats. */
void afterglow_runtime_evaluate_irradiance(const float* sh27, float nx, float ny, float nz,
                                           float* rgb);
/* E/π (rgb) at (x, y, z) for a unit normal from the probes there with their small light sources
 * read as directions (probe_lights.h): closer to the truth than the SH alone beside objects lit
 * by a small lamp. *hint as afterglow_runtime_sample_probes. */
int afterglow_runtime_sample_probe_irradiance(const AfterglowRuntime* runtime, float x, float y,
                                              float z, float nx, float ny, float nz, int* hint,
                                              float* rgb);
/* Refreshes the probes alone (budget_ms > 0: round robin within the budget); stats may be NULL. */
int afterglow_runtime_update_probes(AfterglowRuntime* runtime, double budget_ms,
                                    AfterglowUpdateStats* stats);

/* Reflection probes (runtime.h's "Reflection probes"). Probe 0 is the sky (the fallback outside
 * every box), probe i + 1 the bake's reflection probe i (OUT/probes/reflection_probes.json's
 * index); no probes at all (count 0) when the bake had none. Each is a chain of mip_count
 * cubemaps, mip m for perceptual roughness r with m = r (1.7 - 0.7 r) (mip_count - 1) (Unity's),
 * mip 0 the mirror, its faces +X -X +Y -Y +Z -Z in OpenEXR's cube orientation
 * (runtime/cubemap.h), each face_size^2 texels, rows top to bottom. Reads see the last published
 * reflection update (all black before the first). Functions returning int return 0 for a NULL
 * handle or an invalid index. */
int afterglow_runtime_reflection_probe_count(const AfterglowRuntime* runtime);
int afterglow_runtime_reflection_mip_count(const AfterglowRuntime* runtime);
/* Texels along a face's edge; 0 when invalid. */
int afterglow_runtime_reflection_face_size(const AfterglowRuntime* runtime, int probe, int mip);
/* One face of one mip as face_size^2 * 3 floats (linear RGB radiance, the lightmaps' units).
 * Fails when float_count is below that. */
int afterglow_runtime_read_cubemap(const AfterglowRuntime* runtime, int probe, int mip, int face,
                                   float* rgb, size_t float_count);
/* The (fractional) mip to read for perceptual roughness r, as the bake's shading reads it. */
float afterglow_runtime_reflection_mip_of_roughness(const AfterglowRuntime* runtime, float r);

/* The probes lighting a point and their weights (runtime/reflection_probes.h: importance, smooth
 * fades within each box's blend distance, the sky taking the rest), in increasing probe index:
 * writes up to `capacity` entries into probes[] and weights[] and returns how many there are in
 * all (at least 1: outside every box, or without reflection probes, probe 0 alone with weight
 * 1), which may exceed capacity: call again with room for that many (capacity 0 with NULL
 * arrays only counts). All the entries' weights are > 0 and sum to 1. Returns 0 for a NULL
 * handle, or NULL arrays with a capacity > 0. */
int afterglow_runtime_reflection_probes_at(const AfterglowRuntime* runtime, float x, float y,
                                           float z, int* probes, float* weights, int capacity);

/* A probe's influence box and projection box (ReflectionProbeBox), world space, metres. */
typedef struct AfterglowReflectionProbeBox {
  float centre[3];
  float axes[9];      /* the box's local x, y, z axes in world, orthonormal: axes[3k .. 3k+2] is
                       * axis k (the C++ glm::mat3's columns, in its memory order) */
  float half_size[3]; /* along the local axes; a box not > 0 on every axis is ignored */
  float blend_distance; /* metres inside the faces over which the weight fades in */
  int importance;       /* higher wins where boxes overlap */
  int box_projection;   /* nonzero: parallax-corrected lookups */
  float capture_position[3]; /* where the cubemap was captured */
  /* The box that box projection intersects, on the same axes; a projection_half_size not > 0 on
   * every axis means the influence box itself. */
  float projection_centre[3];
  float projection_half_size[3];
} AfterglowReflectionProbeBox;

/* Probe >= 1's box into *box; 0 for the sky (it has none) or an invalid index. */
int afterglow_runtime_reflection_probe_box(const AfterglowRuntime* runtime, int probe,
                                           AfterglowReflectionProbeBox* box);
/* The parallax-corrected direction (xyz, 3 floats) to look a probe's cubemap up with, for a
 * surface at (px, py, pz) reflecting along (dx, dy, dz) (runtime/reflection_probes.h's
 * boxProject): normalised toward the wall point the reflection reaches, seen from the capture
 * position; the direction unchanged (not normalised) when box projection is off, the box is
 * ignored or the direction is zero. Returns 0 (xyz untouched) for a NULL box or xyz. */
int afterglow_runtime_box_project(const AfterglowReflectionProbeBox* box, float px, float py,
                                  float pz, float dx, float dy, float dz, float* xyz);

/* The split sum's DFG table the cubemaps were shaded with: dfg_size^2 (scale, bias) pairs,
 * row-major, x = NdotV, y = perceptual roughness, texel centres at (i + 0.5) / size; 0 and
 * nothing to read without reflection probes. read_dfg fails when float_count is below
 * 2 * dfg_size^2. */
int afterglow_runtime_dfg_size(const AfterglowRuntime* runtime);
int afterglow_runtime_read_dfg(const AfterglowRuntime* runtime, float* scale_bias,
                               size_t float_count);

/* Runs reflection probe passes alone from the current lightmaps and settings, and publishes
 * them: passes as AfterglowUpdateOptions.reflection_passes (< 0 a full round); budget_ms > 0
 * stops before a pass that would overrun it (the first always runs). stats may be NULL. Returns
 * 0 for a NULL handle or when memory ran out (the cubemaps then keep their last values). */
int afterglow_runtime_update_reflection_probes(AfterglowRuntime* runtime, int passes,
                                               double budget_ms, AfterglowUpdateStats* stats);

#ifdef __cplusplus
}
#endif

#endif /* AFTERGLOW_RUNTIME_H */
