// afterglow_bench accuracy --reference-cache FILE: the reference path tracer's texels kept on
// disk, so that tuning a bake against a converged reference (Sponza at 16,384 paths a texel
// takes minutes on two cores) pays for the reference once. The file records what the reference
// was made of (`key`: the scene and whatever changes its light, such as single-sided emission),
// the paths per texel and every estimated texel's index, position and normal. A texel is reused
// when the key and paths match and it still has that position and normal; the texels a bake
// asks for that the file lacks are computed and added (the reference path tracer seeds each
// texel's paths from the texel alone, so a texel's estimate does not depend on the others).
#pragma once

#include <string>
#include <vector>

#include "afterglow/baker/reference.h"
#include "afterglow/baker/texels.h"

namespace afterglow::bench {

// Every cached texel of `texels` at `spp` paths (those whose position and normal still match),
// or false (absent, unreadable, or made for another key or paths: `why` says which).
bool loadReferenceCache(const std::string& path, const std::string& key,
                        const baker::TexelSet& texels, int spp, baker::ReferenceTexels& out,
                        std::string& why);
// Writes it (AtomicOutput: a killed run leaves no half file).
bool saveReferenceCache(const std::string& path, const std::string& key,
                        const baker::TexelSet& texels, int spp, const baker::ReferenceTexels& ref);

// The reference for `subset` of the texels, in its order, at options.samples paths: those the
// cache at `cachePath` holds read from it, the others computed and added to it (no cache when
// `cachePath` is empty). Prints a line saying what the cache gave.
Result<baker::ReferenceTexels> referenceWithCache(const scenes::Scene& scene,
                                                  const trace::RayTracer& tracer,
                                                  const baker::TexelSet& texels,
                                                  const baker::Environment& environment,
                                                  const baker::ReferenceOptions& options,
                                                  const std::vector<uint32_t>& subset,
                                                  const std::string& cachePath,
                                                  const std::string& key);

}  // namespace afterglow::bench
