// afterglow_bench accuracy --reference-cache FILE: the reference path tracer's texels kept on
// disk, so that tuning a bake against a converged reference (Sponza at 16,384 paths a texel
// takes minutes on two cores) pays for the reference once. The file records what the reference
// was made of (`key`: the scene and whatever changes its light, such as single-sided emission),
// the paths per texel and every estimated texel's index, position and normal; it is reused only
// when all of them match, else it is recomputed and rewritten.
#pragma once

#include <string>
#include <vector>

#include "afterglow/baker/reference.h"
#include "afterglow/baker/texels.h"

namespace afterglow::bench {

// The cached reference for `texels` at `spp` paths, or false (absent, unreadable, or made for
// other texels or paths: `why` says which).
bool loadReferenceCache(const std::string& path, const std::string& key,
                        const baker::TexelSet& texels, const std::vector<uint32_t>& which, int spp,
                        baker::ReferenceTexels& out, std::string& why);
// Writes it (AtomicOutput: a killed run leaves no half file).
bool saveReferenceCache(const std::string& path, const std::string& key,
                        const baker::TexelSet& texels, int spp, const baker::ReferenceTexels& ref);

}  // namespace afterglow::bench
