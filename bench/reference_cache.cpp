// afterglow_bench accuracy's reference cache (reference_cache.h).
#include "reference_cache.h"

#include <cstdint>
#include <cstdio>
#include <cstring>

#include "afterglow/core/atomic_file.h"
#include "afterglow/trace/raytracer.h"

namespace afterglow::bench {

namespace {

constexpr char kMagic[8] = {'A', 'G', 'R', 'E', 'F', '0', '0', '2'};

// One estimated texel as stored: what identifies it, then the estimates.
struct Record {
  uint32_t texel;
  float position[3], normal[3];
  float direct[3], indirect[3], directVariance[3], indirectVariance[3];
};

void put(float* to, glm::vec3 v) { to[0] = v.x, to[1] = v.y, to[2] = v.z; }
glm::vec3 get(const float* from) { return glm::vec3(from[0], from[1], from[2]); }

}  // namespace

bool loadReferenceCache(const std::string& path, const std::string& key,
                        const baker::TexelSet& texels, int spp, baker::ReferenceTexels& out,
                        std::string& why) {
  std::FILE* f = std::fopen(path.c_str(), "rb");
  if (!f) {
    why = "no cache yet";
    return false;
  }
  char magic[8];
  int32_t fileSpp = 0;
  uint32_t keyLength = 0;
  uint64_t count = 0;
  bool ok = std::fread(magic, 1, 8, f) == 8 && std::memcmp(magic, kMagic, 8) == 0 &&
            std::fread(&keyLength, sizeof keyLength, 1, f) == 1 && keyLength < (1u << 16);
  std::string fileKey(ok ? keyLength : 0, '\0');
  ok = ok && std::fread(fileKey.data(), 1, fileKey.size(), f) == fileKey.size() &&
       std::fread(&fileSpp, sizeof fileSpp, 1, f) == 1 &&
       std::fread(&count, sizeof count, 1, f) == 1 && count < (1ull << 32);
  if (!ok) why = "not a reference cache";
  else if (fileKey != key) ok = false, why = "made for " + fileKey;
  else if (fileSpp != spp) ok = false, why = "made at " + std::to_string(fileSpp) + " paths";
  std::vector<Record> records(ok ? count : 0);
  if (ok && std::fread(records.data(), sizeof(Record), records.size(), f) != records.size())
    ok = false, why = "truncated";
  std::fclose(f);
  if (!ok) return false;
  out = baker::ReferenceTexels();
  for (const Record& r : records) {
    if (r.texel >= texels.size() || get(r.position) != texels.position[r.texel] ||
        get(r.normal) != texels.normal[r.texel])
      continue;  // made for other texels
    out.texels.push_back(r.texel);
    out.direct.push_back(get(r.direct));
    out.indirect.push_back(get(r.indirect));
    out.directVariance.push_back(get(r.directVariance));
    out.indirectVariance.push_back(get(r.indirectVariance));
  }
  return true;
}

bool saveReferenceCache(const std::string& path, const std::string& key,
                        const baker::TexelSet& texels, int spp, const baker::ReferenceTexels& ref) {
  std::vector<Record> records(ref.texels.size());
  for (size_t i = 0; i < records.size(); ++i) {
    Record& r = records[i];
    r.texel = ref.texels[i];
    put(r.position, texels.position[r.texel]);
    put(r.normal, texels.normal[r.texel]);
    put(r.direct, ref.direct[i]);
    put(r.indirect, ref.indirect[i]);
    put(r.directVariance, ref.directVariance[i]);
    put(r.indirectVariance, ref.indirectVariance[i]);
  }
  const int32_t fileSpp = spp;
  const uint64_t count = records.size();
  std::string bytes(kMagic, 8);
  const uint32_t keyLength = uint32_t(key.size());
  bytes.append(reinterpret_cast<const char*>(&keyLength), sizeof keyLength);
  bytes.append(key);
  bytes.append(reinterpret_cast<const char*>(&fileSpp), sizeof fileSpp);
  bytes.append(reinterpret_cast<const char*>(&count), sizeof count);
  bytes.append(reinterpret_cast<const char*>(records.data()), records.size() * sizeof(Record));
  AtomicOutput output;
  if (!output.write(path, bytes) || !output.commit()) return false;
  return true;
}

namespace {

// Texel i of `from`, appended to `to`.
void appendTexel(baker::ReferenceTexels& to, const baker::ReferenceTexels& from, size_t i) {
  to.texels.push_back(from.texels[i]);
  to.direct.push_back(from.direct[i]);
  to.indirect.push_back(from.indirect[i]);
  to.directVariance.push_back(from.directVariance[i]);
  to.indirectVariance.push_back(from.indirectVariance[i]);
}

}  // namespace

Result<baker::ReferenceTexels> referenceWithCache(const scenes::Scene& scene,
                                                  const trace::RayTracer& tracer,
                                                  const baker::TexelSet& texels,
                                                  const baker::Environment& environment,
                                                  const baker::ReferenceOptions& options,
                                                  const std::vector<uint32_t>& subset,
                                                  const std::string& cachePath,
                                                  const std::string& key) {
  std::string why;
  baker::ReferenceTexels cached;
  if (!cachePath.empty() &&
      !loadReferenceCache(cachePath, key, texels, options.samples, cached, why))
    std::printf("reference    %s: %s\n", cachePath.c_str(), why.c_str());
  std::vector<uint32_t> cachedAt(texels.size(), UINT32_MAX), missing;
  for (size_t i = 0; i < cached.texels.size(); ++i) cachedAt[cached.texels[i]] = uint32_t(i);
  for (uint32_t t : subset)
    if (cachedAt[t] == UINT32_MAX) missing.push_back(t);
  if (!missing.empty()) {
    Result<baker::ReferenceTexels> fresh =
        baker::referenceTexels(scene, tracer, texels, environment, options, missing);
    if (!fresh) return fresh.status();
    for (size_t i = 0; i < fresh->texels.size(); ++i) {
      cachedAt[fresh->texels[i]] = uint32_t(cached.texels.size());
      appendTexel(cached, fresh.value(), i);
    }
    if (!cachePath.empty() && !saveReferenceCache(cachePath, key, texels, options.samples, cached))
      return Status::error("cannot write the reference cache " + cachePath);
  }
  if (!cachePath.empty())
    std::printf("reference    %zu texels read from %s, %zu computed\n",
                subset.size() - missing.size(), cachePath.c_str(), missing.size());
  baker::ReferenceTexels out;
  for (uint32_t t : subset) appendTexel(out, cached, cachedAt[t]);
  return out;
}

}  // namespace afterglow::bench
