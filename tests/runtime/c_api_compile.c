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
