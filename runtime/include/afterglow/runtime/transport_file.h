// The transport file (OUT/transport.agt): TransportData on disk, written by the bake and loaded
// by engines. GLM and the standard library only, like the rest of the runtime.
//
// Format, version 8. Everything is little-endian; floats are IEEE binary32, halves binary16.
//
//   header (40 bytes, at 0)
//     0  char[8]  magic "AGLOWTR\0"
//     8  u32      format version (kTransportVersion)
//    12  u32      header size (40): where the section table starts
//    16  u64      file size in bytes
//    24  u32      section count
//    28  u32      flags, 0 (reserved)
//    32  u64      checksum: XXH64 of bytes [40, file size) seeded with XXH64 of bytes [0, 32)
//                 (seed 0), so it covers every byte of the file but its own eight
//   section table (at 40): per section 32 bytes
//     char[4] id, u32 0 (reserved), u64 offset, u64 byte size, u64 element count
//   section payloads: each at an offset that is a multiple of 16, in ascending order, not
//     overlapping each other or the table; zero padding between them and up to the file size,
//     which is a multiple of 16.
//
// A section payload is a sequence of fields read in a fixed order, with nothing left over:
//   scalars    u8/u16/u32/i32/f32 at the current position, unaligned (vec3 = 3 f32)
//   strings    u32 byte length, then that many UTF-8 bytes (no terminator, no alignment)
//   arrays     padding to the next multiple of 16 from the section start, u64 element count,
//              8 bytes of padding, then the elements packed: every array's data starts 16-byte
//              aligned in the file, so it can be memcpy'd in one go (or used in place).
//
// Sections of version 8 (all required; any other id is skipped, so a later writer of the same
// version may add sections that older readers ignore). "count" is the table's element count,
// which the reader checks against the payload.
//   INFO  count 1: u32 texelCount, u32 clusterCount, u32 gatherPointCount, i32 filterPasses,
//         f32 indirectIntensity, f32 albedoBoost, 9 × vec3 skySh (132 bytes)
//   ATLS  count = atlases; per atlas: i32 width, i32 height, arrays u32 texelOfPixel,
//         u32 mixPixel, u32 mixStart, u32 mixTexel, f32 mixWeight
//   MATL  count = materials; per material: string name, vec3 albedo, vec3 emission
//   SRCS  count = sources; per source: string name, u8 kind (0 light, 1 emissive),
//         u8 enabled (0/1), u8 light mode (0 baked, 1 mixed, 2 realtime), u8 0, u32 material, vec3 color, f32 intensity,
//         f32 bounceIntensity, arrays f32 texelTransfer, f32 clusterTransfer,
//         f32 probeTransfer (probes × 9: the radiance SH the source sends each probe directly)
//   CLUS  count = clusters: arrays u32 clusterMaterial, vec3 clusterAlbedoTexture,
//         vec3 clusterEmissionTexture
//   FARC  count = far clusters: arrays u32 rowStart, u32 column, f32 weight (far cluster ->
//         clusters)
//   SFAR  count = shared far fields: u32 targetBits, arrays u32 rowStart, u32 link, f32
//         rowScale (as LINK; targets are clusters and far clusters)
//   LINK  count = rows: u32 targetBits, arrays u32 rowStart, u32 link, f32 rowScale (a link
//         packs target | weight code << targetBits: see SparseLinks; every row holds a
//         multiple of kLinkGroup entries, padded with code 0)
//   CGAT  count = rows: cluster gather, arrays u32 rowStart, u32 column, f32 weight
//   GMAP  count = texels: arrays u32 texelPoint, u8 texelNeighbours (the source of the gather
//         point filter and the texel gather, which the reader rebuilds: buildGatherMaps)
//   TSKY  count = values: array u16 texelSky (half floats)
//   CSKY  count = values: array u16 clusterSky (half floats)
//   PROB  count = light probes (0 when the bake had none): u32 bins (regions per probe),
//         arrays vec3 positions, ivec4 tetrahedra, ivec4 neighbours, f32 binSh (bins × 9),
//         then the links as LINK (u32 targetBits, arrays rowStart, link, rowScale; a row per
//         probe and region, targets are clusters and far clusters), array u16 sky (probes ×
//         45 half floats: the sky transfer's upper triangle), array u16 depth (empty, or
//         probes × 128 half floats: probe_visibility.h). See runtime::ProbeTransport.
//   REFL  count = reflection probes (0 when the bake had none): u32 bounces, array vec3
//         bakedAlbedo (per material, or empty), then per probe: string name, u32 resolution,
//         u64 firstHit, vec3 centre, 3 × vec3 axes (columns), vec3 halfSize, f32
//         blendDistance, i32 importance, u32 boxProjection (0/1), vec3 capturePosition, vec3
//         projectionCentre, vec3 projectionHalfSize; then
//         array hits (44 bytes each, runtime::ReflectionHit's layout: u32 material, u16 atlas,
//         u16 roughness (half), 2 × f32 lightmap UV, 3 × u16 diffuse, 3 × u16 emission,
//         3 × u16 F0, 3 × u16 normal (halves), f32 distance). See reflection_capture.h.
//   LAYR  count = lightmap texels (0 for a transport of one resolution, whose texels are the
//         lightmap's): u32 texelCount (the same), u32 atlases, per atlas the fields of an ATLS
//         atlas (the lightmap atlases; their texels are lightmap texels), array corners (8 bytes
//         each, runtime::IndirectCorners' layout: u16 x, u16 y, u8 atlas, u8 fraction, u8 mask,
//         u8 reserved), u32 sources (as SRCS, or 0), per source array u16 direct (half floats,
//         empty or one per lightmap texel), array f32 directScale (per source). When texelCount
//         is not 0 the sections above describe the indirect grid (ATLS, TSKY, GMAP), and the
//         sources' texel transfer is empty. See runtime::LightmapLayers.
// (rows = the rowStart array's length minus one.)
//
// The reader checks, in this order: magic, version, header and file sizes, checksum, the section
// table (every section inside the file, aligned, ascending, no duplicates, required ones present),
// then each payload field against what is left of its section before allocating anything, so no
// input makes it allocate much more than the file's size; then the gather map source
// (checkGatherSource), from which it rebuilds the texel gather and the gather point filter
// (buildGatherMaps); then TransportData::validate() (every index within its counts), whose
// complaint is reported against the section it concerns.
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include "afterglow/runtime/transport.h"

namespace afterglow::runtime {

// 2: 4-byte links, far clusters, gather map source; 3: shared far fields; 4: link rows padded
// to fours; 6: reflection probes; 7: the light probes' depth maps; 8: lightmap layers (LAYR);
// 9: cluster and gather point positions for directional lightmaps (GEOM)
constexpr uint32_t kTransportVersion = 9;
constexpr char kTransportMagic[8] = {'A', 'G', 'L', 'O', 'W', 'T', 'R', '\0'};
constexpr uint32_t kTransportHeaderSize = 40;

// The file's bytes, exactly what saveTransport writes. Any TransportData serialises (even one
// that validate() rejects, which parseTransport then refuses); throws std::bad_alloc only.
std::vector<uint8_t> serializeTransport(const TransportData& data);

// Writes `path` (not atomically: the baker writes a temporary name and renames it; after a failed
// write, whatever was written is left for the caller to remove). Refuses data that validate()
// rejects, since no reader would accept the file. On failure returns false and sets *error (when
// error is not null) to one line starting with the path.
bool saveTransport(const TransportData& data, const std::string& path, std::string* error);

struct ParseOptions {
  // Off only for the fuzzer, so that its mutations reach the section parser.
  bool verifyChecksum = true;
};

// Parses a whole file image. Never throws, crashes or allocates much beyond `size` bytes on bad
// input: returns false, leaves `out` empty (a default TransportData) and sets *error (when not
// null) to one line naming what is wrong, e.g. "truncated: the file has 100 bytes, its header
// says 4096" or "section 'LINK': links: entry 3 refers to 9 of 8".
bool parseTransport(const uint8_t* bytes, size_t size, TransportData& out, std::string* error,
                    const ParseOptions& options = {});

// Reads the file with one read and parses it; errors start with the path
// ("out/transport.agt: checksum mismatch: the file is corrupted").
bool loadTransport(const std::string& path, TransportData& out, std::string* error);

// XXH64 (xxHash's 64-bit hash, bit-exact with the reference implementation).
uint64_t xxh64(const void* data, size_t size, uint64_t seed);

// The checksum a file image should carry at offset 32 given its other bytes (see the format
// above); `size` must be at least kTransportHeaderSize. For tools that patch files, and tests.
uint64_t transportChecksum(const uint8_t* bytes, size_t size);

}  // namespace afterglow::runtime
