// Nearest-in-sight searches over candidate texels, many traced at once (SightSearch): how a
// gather batch finds the stand-ins and light matches of its hits (TexelOfHit).
#pragma once

#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <memory>
#include <utility>
#include <vector>

#include "afterglow/runtime/transport.h"
#include "afterglow/trace/raytracer.h"

namespace afterglow::baker {

// RayTracer::occluded's answers, one per ray, in a buffer kept between calls and grown as
// needed (no fill: occluded writes every entry).
class OcclusionFlags {
 public:
  bool* reserve(size_t rays) {
    if (size_ < rays) {
      size_ = rays;
      flags_.reset(new bool[size_]);
    }
    return flags_.get();
  }
  bool operator[](size_t i) const { return flags_[i]; }

 private:
  std::unique_ptr<bool[]> flags_;
  size_t size_ = 0;
};

// Searches for the nearest candidate texel of each kind whose sample a hit point sees, many
// searches at once (TexelOfHit's stand-in and light match): each search's candidates sorted by
// distance, then rounds that trace the next candidate of every search still open as one ray
// stream. The same texels as testing candidates one by one in visit order (ties go to the
// first visited), and no more sight lines: a candidate is only tested while nothing nearer of
// its kind has been seen.
class SightSearch {
 public:
  static constexpr int kKinds = 2;
  void clear() {
    candidates_.clear();
    searches_.clear();
  }
  // Opens a search from hit `ray` of the batch, on behalf of texel `texel`; returns its index.
  uint32_t open(uint32_t ray, uint32_t texel) {
    const uint32_t at = uint32_t(candidates_.size());
    searches_.push_back({ray, texel, at, at, {}, {}});
    return uint32_t(searches_.size() - 1);
  }
  // Adds a candidate to the last search opened.
  void add(uint32_t texel, float distance, int kind) {
    candidates_.push_back({distance, uint32_t(candidates_.size()), texel, uint8_t(kind)});
    searches_.back().end = uint32_t(candidates_.size());
  }
  // Runs every search. line(search's ray, search's texel, candidate, Ray&) gives the sight
  // line, false when none is needed (the hit point is at the candidate's sample).
  template <class Line>
  void run(const trace::RayTracer& tracer, Line&& line) {
    for (Search& s : searches_) {
      std::sort(candidates_.begin() + s.begin, candidates_.begin() + s.end,
                [](const Candidate& a, const Candidate& b) {
                  return a.distance < b.distance || (a.distance == b.distance && a.order < b.order);
                });
      for (int k = 0; k < kKinds; ++k) s.next[k] = s.begin, s.found[k] = runtime::kNoTexel;
    }
    for (;;) {
      rays_.clear();
      tested_.clear();
      for (uint32_t i = 0; i < searches_.size(); ++i) {
        Search& s = searches_[i];
        for (int k = 0; k < kKinds; ++k) {
          // The kind's next candidate; those that need no line are seen at once.
          while (s.found[k] == runtime::kNoTexel && s.next[k] < s.end) {
            const Candidate& c = candidates_[s.next[k]];
            if (c.kind != k) {
              ++s.next[k];
              continue;
            }
            trace::Ray ray;
            if (!line(s.ray, s.texel, c.texel, ray)) {
              s.found[k] = c.texel;
              break;
            }
            rays_.push_back(ray);
            tested_.push_back({i, k});
            break;
          }
        }
      }
      if (rays_.empty()) return;
      tracer.occluded(rays_.data(), blocked_.reserve(rays_.size()), rays_.size());
      for (size_t j = 0; j < rays_.size(); ++j) {
        Search& s = searches_[tested_[j].first];
        const int k = tested_[j].second;
        if (blocked_[j]) ++s.next[k];
        else s.found[k] = candidates_[s.next[k]].texel;
      }
    }
  }
  size_t size() const { return searches_.size(); }
  uint32_t ray(uint32_t search) const { return searches_[search].ray; }
  uint32_t texel(uint32_t search) const { return searches_[search].texel; }
  // The nearest candidate of `kind` in sight, or kNoTexel.
  uint32_t nearest(uint32_t search, int kind) const { return searches_[search].found[kind]; }

 private:
  struct Candidate {
    float distance;
    uint32_t order;  // visit order, for ties
    uint32_t texel;
    uint8_t kind;
  };
  struct Search {
    uint32_t ray, texel, begin, end;
    uint32_t next[kKinds];   // per kind, the candidate to test next
    uint32_t found[kKinds];  // per kind, the nearest in sight (kNoTexel: none yet)
  };
  std::vector<Candidate> candidates_;
  std::vector<Search> searches_;
  std::vector<trace::Ray> rays_;
  std::vector<std::pair<uint32_t, int>> tested_;  // per ray of a round: search, kind
  OcclusionFlags blocked_;
};

}  // namespace afterglow::baker
