/* Compiled as strict C99 (-pedantic-errors): proves afterglow_runtime.h is valid C. The functions
 * run from runtime_api_test.cpp, which checks their results against the C++ API. */
#include "afterglow_runtime.h"

#include <string.h>

/* Loads `path`, applies a fixed set of changes through every setter, runs 4 bounces from scratch
 * and reads atlas 0 into rgb. Returns 1 when every call behaved as documented. */
int afterglow_test_c_relight(const char* path, float* rgb, size_t float_count, char* err,
                             size_t err_size) {
  AfterglowUpdateOptions options;
  AfterglowUpdateStats stats;
  float sh[27];
  int ok = 1, fill, wall, lamp, i;
  AfterglowRuntime* rt = afterglow_runtime_load(path, err, err_size);
  if (!rt) return 0;

  fill = afterglow_runtime_find_light(rt, "fill");
  wall = afterglow_runtime_find_material(rt, "wall");
  lamp = afterglow_runtime_find_material(rt, "lamp");
  ok &= fill >= 0 && wall >= 0 && lamp >= 0;
  ok &= afterglow_runtime_find_light(rt, "no such light") == -1;
  ok &= afterglow_runtime_light_count(rt) == 3 && afterglow_runtime_material_count(rt) == 3;
  ok &= strcmp(afterglow_runtime_light_name(rt, fill), "fill") == 0;
  ok &= strcmp(afterglow_runtime_material_name(rt, lamp), "lamp") == 0;
  ok &= afterglow_runtime_light_name(rt, 99) == NULL;

  ok &= afterglow_runtime_set_light_color(rt, fill, 0.25f, 0.5f, 2.0f);
  ok &= afterglow_runtime_set_light_intensity(rt, fill, 3.0f);
  ok &= afterglow_runtime_set_bounce_intensity(rt, 0, 0.5f);
  ok &= afterglow_runtime_set_light_enabled(rt, 2, 0);
  ok &= !afterglow_runtime_set_light_color(rt, 3, 1.0f, 1.0f, 1.0f);
  for (i = 0; i < 27; ++i) sh[i] = 0.01f * (float)i;
  ok &= afterglow_runtime_set_sky_sh(rt, sh);
  ok &= afterglow_runtime_set_sky(rt, 0.1f, 0.2f, 0.3f);
  ok &= afterglow_runtime_set_albedo(rt, wall, 0.3f, 0.4f, 0.5f);
  ok &= afterglow_runtime_can_set_emission(rt, lamp) && !afterglow_runtime_can_set_emission(rt, wall);
  ok &= afterglow_runtime_set_emission(rt, lamp, 1.0f, 2.0f, 3.0f);
  ok &= !afterglow_runtime_set_emission(rt, wall, 1.0f, 2.0f, 3.0f);
  ok &= afterglow_runtime_set_indirect_intensity(rt, 1.25f);

  afterglow_runtime_default_options(&options);
  options.max_bounces = 4;
  options.from_scratch = 1;
  ok &= afterglow_runtime_update(rt, &options, &stats);
  ok &= stats.bounces == 4;
  ok &= afterglow_runtime_atlas_count(rt) >= 1;
  ok &= !afterglow_runtime_read_atlas(rt, 0, rgb, 2); /* too small */
  ok &= afterglow_runtime_read_atlas(rt, 0, rgb, float_count);
  afterglow_runtime_free(rt);
  return ok;
}

/* The light probe calls on a transport with five probes: out receives probe 2's SH (27 floats),
 * the SH sampled at (0.25, 0.25, 0.25) (27), probe 2's position (3), then 3 unused floats and
 * the irradiance of the sampled SH for the normal (1, 2, 3) normalised (3). Returns 1 when
 * every call behaved as documented. */
int afterglow_test_c_probes(const char* path, float* out) {
  AfterglowUpdateOptions options;
  AfterglowUpdateStats stats;
  char err[256];
  int ok = 1, hint = 0;
  const float n = 1.0f / 3.7416574f; /* 1 / |(1, 2, 3)| */
  AfterglowRuntime* rt = afterglow_runtime_load(path, err, sizeof err);
  if (!rt) return 0;
  afterglow_runtime_default_options(&options);
  ok &= options.probes == 1;
  options.max_bounces = 4;
  options.from_scratch = 1;
  ok &= afterglow_runtime_update(rt, &options, &stats);
  ok &= stats.probes == 5;
  ok &= afterglow_runtime_probe_count(rt) == 5;
  ok &= afterglow_runtime_probe_sh(rt, 2, out);
  ok &= !afterglow_runtime_probe_sh(rt, 5, out + 54);
  ok &= afterglow_runtime_sample_probes(rt, 0.25f, 0.25f, 0.25f, &hint, out + 27);
  ok &= afterglow_runtime_probe_position(rt, 2, out + 54);
  afterglow_runtime_evaluate_irradiance(out + 27, n, 2.0f * n, 3.0f * n, out + 60);
  hint = 0;
  ok &= afterglow_runtime_sample_probe_irradiance(rt, 0.25f, 0.25f, 0.25f, n, 2.0f * n, 3.0f * n,
                                                  &hint, out + 63);
  ok &= afterglow_runtime_update_probes(rt, 0.0, &stats) && stats.probes == 5;
  ok &= afterglow_runtime_probe_count(NULL) == 0;
  afterglow_runtime_free(rt);
  return ok;
}

/* afterglow_runtime_load's failure path: returns 1 when it returned NULL. */
int afterglow_test_c_load_fails(const char* path, char* err, size_t err_size) {
  AfterglowRuntime* rt = afterglow_runtime_load(path, err, err_size);
  if (rt) {
    afterglow_runtime_free(rt);
    return 0;
  }
  afterglow_runtime_free(NULL);
  return 1;
}

/* The reflection probe calls on a transport with two reflection probes (2^2 and 4^2 faces, two
 * bounces) and no other change: a full round from scratch after the sky is set to (0.1, 0.2,
 * 0.3), then writes cube: probe 2's mip 0 face 3 (48 floats) and probe 1's mip 1 face 0 (3);
 * projected: probe 1's box projection at (0.5, 0.5, 0.5) along (1, 2, -3) (3 floats); probes,
 * weights (room for 4) and *count: the probes at (0.5, 0.5, 0.5); box: probe 2's box. Returns 1
 * when every call behaved as documented. */
int afterglow_test_c_reflections(const char* path, float* cube, float* projected, int* probes,
                                 float* weights, int* count, AfterglowReflectionProbeBox* box) {
  AfterglowUpdateOptions options;
  AfterglowUpdateStats stats;
  char err[256];
  static float dfg[2 * 64 * 64];
  float black[12];
  int ok = 1, n, i;
  AfterglowRuntime* rt = afterglow_runtime_load(path, err, sizeof err);
  if (!rt) return 0;
  afterglow_runtime_default_options(&options);
  ok &= options.reflection_passes < 0; /* a full round */

  ok &= afterglow_runtime_reflection_probe_count(rt) == 3;
  ok &= afterglow_runtime_reflection_mip_count(rt) == 7;
  ok &= afterglow_runtime_reflection_face_size(rt, 0, 0) == 64; /* the sky */
  ok &= afterglow_runtime_reflection_face_size(rt, 1, 0) == 2;
  ok &= afterglow_runtime_reflection_face_size(rt, 2, 1) == 2;
  ok &= afterglow_runtime_reflection_face_size(rt, 2, 6) == 1;
  ok &= afterglow_runtime_reflection_face_size(rt, 2, 7) == 0;
  ok &= afterglow_runtime_reflection_face_size(rt, 3, 0) == 0;
  /* Black before the first update. */
  for (i = 0; i < 12; ++i) black[i] = -1.0f;
  ok &= afterglow_runtime_read_cubemap(rt, 1, 0, 5, black, 12);
  for (i = 0; i < 12; ++i) ok &= black[i] == 0.0f;

  ok &= afterglow_runtime_set_sky(rt, 0.1f, 0.2f, 0.3f);
  options.max_bounces = 4;
  options.from_scratch = 1;
  ok &= afterglow_runtime_update(rt, &options, &stats);
  ok &= stats.reflection_passes == 6; /* (2 bounces + 1) x 2 probes */
  ok &= stats.reflection_milliseconds >= 0.0 && stats.reflection_milliseconds <= stats.milliseconds;

  ok &= afterglow_runtime_read_cubemap(rt, 2, 0, 3, cube, 48);
  ok &= afterglow_runtime_read_cubemap(rt, 1, 1, 0, cube + 48, 3);
  ok &= !afterglow_runtime_read_cubemap(rt, 2, 0, 3, black, 12); /* too small */
  ok &= !afterglow_runtime_read_cubemap(rt, 2, 0, 6, black, 12); /* no face 6 */
  ok &= !afterglow_runtime_read_cubemap(rt, 3, 0, 0, black, 12); /* no probe 3 */
  ok &= !afterglow_runtime_read_cubemap(rt, 1, 0, 0, NULL, 12);
  ok &= afterglow_runtime_reflection_mip_of_roughness(rt, 0.0f) == 0.0f;
  ok &= afterglow_runtime_reflection_mip_of_roughness(rt, 1.0f) > 5.999f;
  ok &= afterglow_runtime_reflection_mip_of_roughness(rt, 1.0f) < 6.001f;

  /* Count first, then fill. */
  n = afterglow_runtime_reflection_probes_at(rt, 0.5f, 0.5f, 0.5f, NULL, NULL, 0);
  ok &= n >= 1 && n <= 3;
  *count = afterglow_runtime_reflection_probes_at(rt, 0.5f, 0.5f, 0.5f, probes, weights, 4);
  ok &= *count == n;
  ok &= afterglow_runtime_reflection_probes_at(rt, 0.5f, 0.5f, 0.5f, NULL, NULL, 1) == 0;

  ok &= !afterglow_runtime_reflection_probe_box(rt, 0, box); /* the sky has none */
  ok &= !afterglow_runtime_reflection_probe_box(rt, 3, box);
  ok &= afterglow_runtime_reflection_probe_box(rt, 1, box);
  ok &= afterglow_runtime_box_project(box, 0.5f, 0.5f, 0.5f, 1.0f, 2.0f, -3.0f, projected);
  ok &= !afterglow_runtime_box_project(NULL, 0.5f, 0.5f, 0.5f, 1.0f, 2.0f, -3.0f, projected);
  ok &= afterglow_runtime_reflection_probe_box(rt, 2, box);

  ok &= afterglow_runtime_dfg_size(rt) == 64;
  ok &= !afterglow_runtime_read_dfg(rt, dfg, 2 * 64 * 64 - 1);
  ok &= afterglow_runtime_read_dfg(rt, dfg, 2 * 64 * 64);
  for (i = 0; i < 2 * 64 * 64; ++i) ok &= dfg[i] >= 0.0f && dfg[i] <= 1.0f;

  /* One unit alone: pass 0 of probe 1. */
  ok &= afterglow_runtime_update_reflection_probes(rt, 1, 0.0, &stats);
  ok &= stats.reflection_passes == 1 && stats.bounces == 0;
  ok &= afterglow_runtime_update_reflection_probes(rt, 1, 0.0, NULL);

  ok &= afterglow_runtime_reflection_probe_count(NULL) == 0;
  ok &= afterglow_runtime_read_cubemap(NULL, 1, 0, 0, black, 12) == 0;
  ok &= afterglow_runtime_update_reflection_probes(NULL, -1, 0.0, NULL) == 0;
  afterglow_runtime_free(rt);
  return ok;
}
