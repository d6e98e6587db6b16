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
 * Threads: setters, getters and read_atlas/read_texels may run concurrently with each other and
 * with afterglow_runtime_update (reads see one whole completed update); updates are serialised.
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
} AfterglowUpdateOptions;

typedef struct AfterglowUpdateStats {
  int bounces;         /* passes run */
  int converged;       /* 1 when the last pass changed less than the tolerance */
  float change;        /* the last pass's largest relative change (0 when none ran) */
  double milliseconds; /* wall time of the call */
  int probes;                /* light probes refreshed */
  double probe_milliseconds; /* of which the probes took */
} AfterglowUpdateStats;

/* The defaults: max_bounces 0, tolerance 1e-3, no budget, warm start. */
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
 * NULL. Returns 0 only for a NULL handle. */
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
/* Tetrahedral interpolation at (x, y, z); *hint (may be NULL) starts the walk and receives the
 * tetrahedron found. */
int afterglow_runtime_sample_probes(const AfterglowRuntime* runtime, float x, float y, float z,
                                    int* hint, float* sh27);
/* E/π (rgb) for a unit normal from 27 SH floats. */
void afterglow_runtime_evaluate_irradiance(const float* sh27, float nx, float ny, float nz,
                                           float* rgb);
/* Refreshes the probes alone (budget_ms > 0: round robin within the budget); stats may be NULL. */
int afterglow_runtime_update_probes(AfterglowRuntime* runtime, double budget_ms,
                                    AfterglowUpdateStats* stats);

#ifdef __cplusplus
}
#endif

#endif /* AFTERGLOW_RUNTIME_H */
