// Chart packing: conservative texel footprints placed bottom-left-first into bitmap atlases.
//
// Each chart is turned to its minimum-area bounding rectangle (wide side along x), rasterised
// conservatively into a small bitmap, and placed at an integer texel position, so the footprint
// bitmap is exactly the set of atlas texels the chart touches. The atlas stores footprints dilated
// by `padding` (Chebyshev), and a chart fits where its raw footprint meets no stored bit: any two
// footprints then have at least `padding` empty texels between them, along rows, columns and
// diagonals. Charts go in by decreasing size; the small ones fill the holes the big ones leave.
//
// The position search tests every column of an atlas row at once: for each run of set bits in
// the chart's mask row, "some stored bit under the run" is an OR of shifted atlas words, and the
// candidates are what no row rules out. Before any bit work, a per-row longest free run and
// per-row masks of non-full and empty 64-texel words rule out most rows, and identical footprints
// (instances of one mesh) resume where the previous one's search ended.
//
// How well the last rows fill depends on the atlas width in a way no estimate predicts (±3%
// utilisation on Sponza), so the big charts are packed at several widths and the two best
// predicted layouts are packed in full, in parallel; the smaller total area wins.
#include "afterglow/uv/pack.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <numeric>
#include <unordered_map>

#include "afterglow/core/parallel.h"
#include "afterglow/uv/texel_raster.h"

namespace afterglow::uv {
namespace {

using Word = uint64_t;
constexpr Word kAll = ~Word(0);
constexpr double kSnap = 1e-4;  // texels
constexpr double kExpectedFill = 0.9;  // share of an atlas the padded footprints fill
// Atlas widths tried, as factors of the square at the expected fill.
constexpr double kWidthFactors[] = {1.0, 0.85, 0.9, 0.95, 1.05, 1.1, 1.15, 1.2, 1.25};
constexpr size_t kFullAttempts = 2;  // widths packed in full after the trial of the big charts
constexpr double kBigShare = 0.7;    // share of the padded area in the trial's big charts

int roundUp4(int v) { return (v + 3) & ~3; }

// One bit per texel; rows of `stride` words, the last of which is always zero so that reading 64
// bits from any column inside a row never leaves it.
struct Bitmap {
  int width = 0, height = 0, words = 0, stride = 0;
  std::vector<Word> bits;

  void reset(int w, int h) {
    width = w;
    height = h;
    words = (w + 63) / 64;
    stride = words + 1;
    bits.assign(size_t(stride) * size_t(h), 0);
  }
  Word* row(int y) { return bits.data() + size_t(y) * size_t(stride); }
  const Word* row(int y) const { return bits.data() + size_t(y) * size_t(stride); }
  bool get(int x, int y) const { return (row(y)[x >> 6] >> (x & 63)) & 1; }
  void set(int x, int y) { row(y)[x >> 6] |= Word(1) << (x & 63); }
};

// 64 bits of `row` (n words) starting at bit `pos` >= 0, zero past the end.
inline Word bitsAt(const Word* row, long n, long pos) {
  const long w = pos >> 6;
  const int sh = int(pos & 63);
  if (w >= n) return 0;
  const Word lo = row[w] >> sh;
  if (sh == 0 || w + 1 >= n) return lo;
  return lo | (row[w + 1] << (64 - sh));
}

// Bit x set when any of the `len` (<= 64) bits from pos + x is set, for x in [0, 64).
inline Word anyInWindow(const Word* row, long n, long pos, int len) {
  unsigned __int128 x = (unsigned __int128)bitsAt(row, n, pos + 64) << 64 | bitsAt(row, n, pos);
  for (int cur = 1; cur < len;) {
    const int s = std::min(cur, len - cur);
    x |= x >> s;
    cur += s;
  }
  return Word(x);
}

struct Run {
  int c0, len;  // first column and length of a run of set bits in one mask row
};

// One orientation of a chart.
struct Variant {
  bool valid = false;
  glm::mat2 rotation{1.0f};
  glm::dvec2 shift{0.0};  // offset = placement position + shift
  int cols = 0, rows = 0;
  size_t count = 0;       // texels in the footprint
  Bitmap raw;             // cols x rows
  Bitmap dilated;         // (cols + 2 padding) x (rows + 2 padding), origin at -padding
  std::vector<std::vector<Run>> runs;  // per mask row
  std::vector<int> rowMaxRun;          // longest run per mask row
  std::vector<int> testOrder;          // non-empty mask rows, longest run first
  uint64_t shapeHash = 0;              // identical footprints share it (search memo)
};

struct Prepared {
  bool valid = false;
  Variant v[2];
  long long sizeKey = 0;  // packing order: larger first
  long long estArea = 0;  // padded area for sizing the atlas
};

glm::mat2 fromRows(double r00, double r01, double r10, double r11) {
  glm::mat2 m;
  m[0][0] = float(r00);
  m[1][0] = float(r01);
  m[0][1] = float(r10);
  m[1][1] = float(r11);
  return m;
}

double cross(const glm::dvec2& o, const glm::dvec2& a, const glm::dvec2& b) {
  return (a.x - o.x) * (b.y - o.y) - (a.y - o.y) * (b.x - o.x);
}

std::vector<glm::dvec2> convexHull(std::vector<glm::dvec2> pts) {
  std::sort(pts.begin(), pts.end(), [](const glm::dvec2& a, const glm::dvec2& b) {
    return a.x < b.x || (a.x == b.x && a.y < b.y);
  });
  pts.erase(std::unique(pts.begin(), pts.end()), pts.end());
  if (pts.size() < 3) return pts;
  std::vector<glm::dvec2> hull(2 * pts.size());
  size_t k = 0;
  for (size_t i = 0; i < pts.size(); ++i) {
    while (k >= 2 && cross(hull[k - 2], hull[k - 1], pts[i]) <= 0) --k;
    hull[k++] = pts[i];
  }
  for (size_t i = pts.size() - 1, t = k + 1; i > 0; --i) {
    while (k >= t && cross(hull[k - 2], hull[k - 1], pts[i - 1]) <= 0) --k;
    hull[k++] = pts[i - 1];
  }
  hull.resize(k - 1);
  return hull;
}

// Unit direction of a side of the minimum-area bounding rectangle, in the quadrant x > 0,
// y >= 0. The rectangle has a side along a hull edge, so trying every edge is exact. The axis
// direction wins ties, so axis-aligned charts stay as authored.
glm::dvec2 minAreaDirection(const std::vector<glm::dvec2>& hull) {
  auto area = [&](const glm::dvec2& d) {
    double u0 = 1e300, u1 = -1e300, v0 = 1e300, v1 = -1e300;
    for (const glm::dvec2& p : hull) {
      const double u = p.x * d.x + p.y * d.y, v = -p.x * d.y + p.y * d.x;
      u0 = std::min(u0, u), u1 = std::max(u1, u), v0 = std::min(v0, v), v1 = std::max(v1, v);
    }
    return (u1 - u0) * (v1 - v0);
  };
  glm::dvec2 best(1.0, 0.0);
  double bestArea = area(best);
  for (size_t i = 0; i < hull.size(); ++i) {
    glm::dvec2 e = hull[(i + 1) % hull.size()] - hull[i];
    const double len = std::sqrt(e.x * e.x + e.y * e.y);
    if (!(len > 0.0)) continue;
    glm::dvec2 d = e / len;
    for (int turn = 0; turn < 4 && !(d.x > 0.0 && d.y >= 0.0); ++turn) d = glm::dvec2(-d.y, d.x);
    const double a = area(d);
    if (a < bestArea * (1.0 - 1e-9)) best = d, bestArea = a;
  }
  return best;
}

// Rasterises the chart under `rotation` and builds the masks the placement needs. The chart is
// centred in a whole number of texels per axis (the fewest that can hold it), so the footprint
// never depends on where it lands.
void buildVariant(const PackChart& chart, const glm::mat2& rotation, int padding, int maxSize,
                  Variant& v) {
  v.rotation = rotation;
  const size_t n = chart.triangles.size();
  std::vector<glm::vec2> q(n);
  glm::vec2 lo(std::numeric_limits<float>::max()), hi(-std::numeric_limits<float>::max());
  for (size_t i = 0; i < n; ++i) {
    q[i] = rotation * chart.triangles[i];  // exactly what the unwrap computes
    lo = glm::min(lo, q[i]);
    hi = glm::max(hi, q[i]);
  }
  const glm::dvec2 extent = glm::dvec2(hi) - glm::dvec2(lo);
  // A chart whose extent is a whole number of texels plus float noise from its turn keeps that
  // whole number: the 1e-4 texel that sticks out is far inside the metrics' tolerance.
  const double colsD = std::max(1.0, std::ceil(extent.x - kSnap));
  const double rowsD = std::max(1.0, std::ceil(extent.y - kSnap));
  if (colsD > maxSize || rowsD > maxSize) return;
  v.cols = int(colsD);
  v.rows = int(rowsD);
  const glm::dvec2 margin = (glm::dvec2(colsD, rowsD) - extent) * 0.5;
  v.shift = margin - glm::dvec2(lo);
  v.raw.reset(v.cols, v.rows);
  for (size_t t = 0; t + 2 < n; t += 3) {
    const glm::dvec2 a = glm::dvec2(q[t]) - glm::dvec2(lo) + margin;
    const glm::dvec2 b = glm::dvec2(q[t + 1]) - glm::dvec2(lo) + margin;
    const glm::dvec2 c = glm::dvec2(q[t + 2]) - glm::dvec2(lo) + margin;
    rasterizeTriangle(a, b, c, kPackGrow, v.cols, v.rows,
                              [&](int x, int y) { v.raw.set(x, y); });
  }
  // Runs per row, and the horizontal dilation on the way.
  const int p = padding;
  Bitmap horiz;
  horiz.reset(v.cols + 2 * p, v.rows);
  v.runs.assign(v.rows, {});
  v.rowMaxRun.assign(v.rows, 0);
  v.count = 0;
  for (int y = 0; y < v.rows; ++y) {
    int x = 0;
    while (x < v.cols) {
      if (!v.raw.get(x, y)) {
        ++x;
        continue;
      }
      int e = x;
      while (e < v.cols && v.raw.get(e, y)) ++e;
      v.runs[y].push_back({x, e - x});
      v.rowMaxRun[y] = std::max(v.rowMaxRun[y], e - x);
      v.count += size_t(e - x);
      for (int k = x; k < e + 2 * p; ++k) horiz.set(k, y);
      x = e;
    }
    if (!v.runs[y].empty()) v.testOrder.push_back(y);
  }
  uint64_t h = 1469598103934665603ull ^ (uint64_t(v.cols) << 32) ^ uint64_t(v.rows);
  for (Word w : v.raw.bits) h = (h ^ w) * 1099511628211ull ^ (h >> 29);
  v.shapeHash = h;
  std::stable_sort(v.testOrder.begin(), v.testOrder.end(),
                   [&](int a, int b) { return v.rowMaxRun[a] > v.rowMaxRun[b]; });
  v.dilated.reset(v.cols + 2 * p, v.rows + 2 * p);
  for (int y = 0; y < v.rows; ++y)
    for (int k = 0; k <= 2 * p; ++k) {
      Word* dst = v.dilated.row(y + k);
      const Word* src = horiz.row(y);
      for (int w = 0; w < horiz.words; ++w) dst[w] |= src[w];
    }
  v.valid = true;
}

void prepareChart(const PackChart& chart, int padding, int maxSize, bool allowRotation,
                  Prepared& out) {
  const size_t n = chart.triangles.size() - chart.triangles.size() % 3;
  for (size_t i = 0; i < n; ++i)
    if (!std::isfinite(chart.triangles[i].x) || !std::isfinite(chart.triangles[i].y)) return;
  std::vector<glm::dvec2> pts(n);
  for (size_t i = 0; i < n; ++i) pts[i] = glm::dvec2(chart.triangles[i]);
  const std::vector<glm::dvec2> hull = convexHull(pts);
  const glm::dvec2 d = minAreaDirection(hull);
  // Rows of the rotation: d goes to +x.
  double r[4] = {d.x, d.y, -d.y, d.x};
  double ex = 0.0, ey = 0.0;
  if (!hull.empty()) {
    double u0 = 1e300, u1 = -1e300, v0 = 1e300, v1 = -1e300;
    for (const glm::dvec2& p : hull) {
      const double u = r[0] * p.x + r[1] * p.y, v = r[2] * p.x + r[3] * p.y;
      u0 = std::min(u0, u), u1 = std::max(u1, u), v0 = std::min(v0, v), v1 = std::max(v1, v);
    }
    ex = u1 - u0, ey = v1 - v0;
  }
  if (ey > ex) {  // wide side along x: (x, y) -> (y, -x)
    const double t[4] = {r[2], r[3], -r[0], -r[1]};
    std::copy(t, t + 4, r);
  }
  buildVariant(chart, fromRows(r[0], r[1], r[2], r[3]), padding, maxSize, out.v[0]);
  if (allowRotation) {  // a quarter turn further: (x, y) -> (-y, x)
    buildVariant(chart, fromRows(-r[2], -r[3], r[0], r[1]), padding, maxSize, out.v[1]);
    // A footprint that a quarter turn maps onto itself gains nothing from trying both.
    if (out.v[0].valid && out.v[1].valid && out.v[0].cols == out.v[0].rows &&
        out.v[0].raw.bits == out.v[1].raw.bits)
      out.v[1].valid = false;
  }
  const Variant& base = out.v[0].valid ? out.v[0] : out.v[1];
  if (!base.valid) return;
  out.valid = true;
  // Padded box area orders best of those tried (footprint area, longest side, perimeter).
  out.sizeKey = (long long)(base.cols + padding) * (base.rows + padding);
  // The footprint grown by half the padding all round, as neighbours share the gap.
  out.estArea = (long long)base.count + (long long)padding * (base.cols + base.rows) +
                (long long)padding * padding;
}

class Atlas {
 public:
  Atlas(int width, int maxHeight) : freeRun_(maxHeight, width) {
    occ_.reset(width, maxHeight);
    nfStride_ = (occ_.words + 63) / 64 + 1;
    nonFull_.assign(size_t(nfStride_) * size_t(maxHeight), 0);
    emptyWords_.assign(size_t(nfStride_) * size_t(maxHeight), 0);
    for (int y = 0; y < maxHeight; ++y) updateNonFull(y);
  }

  int width() const { return occ_.width; }
  int usedWidth() const { return usedW_; }
  int usedHeight() const { return usedH_; }

  // Lowest row, then lowest column, where the chart fits with its top at most yTopLimit.
  bool find(const Variant& v, int yTopLimit, int& outX, int& outY) {
    const int W = occ_.width, H = occ_.height;
    if (!v.valid || v.cols > W || v.rows > H) return false;
    if (v.count == 0) {
      outX = 0, outY = 0;
      return true;
    }
    const int xMax = W - v.cols;
    const int kWords = xMax / 64 + 1;
    const int liveWords = (kWords + 63) / 64;
    const Word lastMask = ((xMax & 63) == 63) ? kAll : ((Word(1) << ((xMax & 63) + 1)) - 1);
    k_.resize(kWords);
    e_.resize(kWords);
    live_.resize(liveWords);
    const int yEnd = std::min(H, yTopLimit) - v.rows;
    // Occupancy only grows, so a footprint identical to an earlier one cannot fit below the
    // row where that one's search ended.
    int& memo = shapeStart_[v.shapeHash];
    for (int y = std::max(firstOpen_, memo); y <= yEnd; ++y) {
      int failed = -1;
      for (int r : v.testOrder)
        if (freeRun_[y + r] < v.rowMaxRun[r]) {
          failed = r;
          break;
        }
      if (failed >= 0) {
        // Atlas row t cannot hold mask row `failed`, nor any mask row needing a longer run:
        // jump to the next y that puts a row it can hold (or nothing) on t.
        const int t = y + failed, f = freeRun_[t];
        int r = failed - 1;
        while (r >= 0 && v.rowMaxRun[r] > f) --r;
        y = (r >= 0 ? t - r : t + 1) - 1;
        continue;
      }
      // Word level first: x can only be free of collisions where the atlas words holding the
      // first and the last texel of every run have a free bit. Most rows die here.
      for (int b = 0; b < liveWords; ++b)
        live_[b] = (b == liveWords - 1 && (kWords & 63)) ? (Word(1) << (kWords & 63)) - 1 : kAll;
      Word any = 1;
      for (int r : v.testOrder) {
        const Word* nf = nonFull_.data() + size_t(y + r) * size_t(nfStride_);
        const Word* ew = emptyWords_.data() + size_t(y + r) * size_t(nfStride_);
        for (const Run& run : v.runs[r]) {
          any = 0;
          // Atlas words that lie wholly under the run wherever x is in the K word: all empty.
          const int firstWhole = (run.c0 + 126) / 64;
          const int lastWhole = run.c0 + run.len >= 64 ? (run.c0 + run.len - 64) / 64 : -1;
          for (int b = 0; b < liveWords; ++b) {
            Word m = live_[b] & wordsWithFree(nf, 64 * b, run.c0) &
                     wordsWithFree(nf, 64 * b, run.c0 + run.len - 1);
            for (int d = firstWhole; d <= lastWhole && m; ++d) m &= bitsAt(ew, nfStride_, 64L * b + d);
            live_[b] = m;
            any |= m;
          }
          if (!any) break;
        }
        if (!any) break;
      }
      if (!any) continue;
      // Bit level on the surviving words.
      for (int b = 0; b < liveWords; ++b)
        for (Word m = live_[b]; m; m &= m - 1) {
          const int i = 64 * b + __builtin_ctzll(m);
          k_[i] = i == kWords - 1 ? lastMask : kAll;
        }
      for (int r : v.testOrder) {
        const Word* arow = occ_.row(y + r);
        for (const Run& run : v.runs[r]) {
          any = 0;
          if (run.len > 64) {
            int i0 = -1, i1 = -1;
            for (int b = 0; b < liveWords; ++b)
              if (live_[b]) {
                if (i0 < 0) i0 = 64 * b + __builtin_ctzll(live_[b]);
                i1 = 64 * b + 63 - __builtin_clzll(live_[b]);
              }
            collisions(arow, run, i0, i1);
            for (int b = 0; b < liveWords; ++b) {
              for (Word m = live_[b]; m; m &= m - 1) {
                const int i = 64 * b + __builtin_ctzll(m);
                k_[i] &= ~e_[i - i0];
                if (!k_[i]) live_[b] &= ~(Word(1) << (i & 63));
              }
              any |= live_[b];
            }
          } else {
            const long n = occ_.stride;
            for (int b = 0; b < liveWords; ++b) {
              for (Word m = live_[b]; m; m &= m - 1) {
                const int i = 64 * b + __builtin_ctzll(m);
                k_[i] &= ~anyInWindow(arow, n, 64L * i + run.c0, run.len);
                if (!k_[i]) live_[b] &= ~(Word(1) << (i & 63));
              }
              any |= live_[b];
            }
          }
          if (!any) break;
        }
        if (!any) break;
      }
      if (!any) continue;
      for (int b = 0; b < liveWords; ++b)
        if (live_[b]) {
          const int i = 64 * b + __builtin_ctzll(live_[b]);
          outX = i * 64 + __builtin_ctzll(k_[i]);
          outY = y;
          memo = std::max(memo, y);
          return true;
        }
    }
    memo = std::max(memo, yEnd + 1);
    return false;
  }

  void place(const Variant& v, int x, int y, int padding) {
    if (v.count == 0) return;
    const int W = occ_.width, H = occ_.height;
    for (int dr = 0; dr < v.dilated.height; ++dr) {
      const int ay = y - padding + dr;
      if (ay < 0 || ay >= H) continue;
      Word* dst = occ_.row(ay);
      const Word* src = v.dilated.row(dr);
      for (int w = 0; w < v.dilated.words; ++w)
        if (src[w]) orBits(dst, x - padding + 64 * w, src[w]);
      if (W & 63) dst[occ_.words - 1] &= (Word(1) << (W & 63)) - 1;
      freeRun_[ay] = longestFreeRun(dst);
      updateNonFull(ay);
    }
    usedW_ = std::max(usedW_, x + v.cols);
    usedH_ = std::max(usedH_, y + v.rows);
    while (firstOpen_ < H && freeRun_[firstOpen_] == 0) ++firstOpen_;
  }

 private:
  // Bit j of the result: atlas word (j + first/64 + wordBase) or, when `first` straddles words,
  // the next one has a free texel, i.e. the texel at column x + first may be free for some x in
  // K word j + wordBase.
  Word wordsWithFree(const Word* nf, int wordBase, int first) const {
    const int shift = first >> 6;
    Word m = bitsAt(nf, nfStride_, long(wordBase) + shift);
    if (first & 63) m |= bitsAt(nf, nfStride_, long(wordBase) + shift + 1);
    return m;
  }

  void updateNonFull(int y) {
    Word* nf = nonFull_.data() + size_t(y) * size_t(nfStride_);
    Word* ew = emptyWords_.data() + size_t(y) * size_t(nfStride_);
    std::fill(nf, nf + nfStride_, Word(0));
    std::fill(ew, ew + nfStride_, Word(0));
    const Word* row = occ_.row(y);
    const int W = occ_.width;
    for (int w = 0; w < occ_.words; ++w) {
      const int nb = std::min(64, W - 64 * w);
      const Word full = nb == 64 ? kAll : (Word(1) << nb) - 1;
      if ((row[w] & full) != full) nf[w >> 6] |= Word(1) << (w & 63);
      if ((row[w] & full) == 0) ew[w >> 6] |= Word(1) << (w & 63);
    }
  }

  // e_[i - i0] = bits x of word i where some stored bit lies under the run placed at x.
  void collisions(const Word* arow, const Run& run, int i0, int i1) {
    const long n = occ_.stride;
    if (run.len <= 16) {
      for (int i = i0; i <= i1; ++i) {
        Word e = 0;
        for (int k = 0; k < run.len; ++k) e |= bitsAt(arow, n, 64L * i + run.c0 + k);
        e_[i - i0] = e;
      }
      return;
    }
    // Doubling: after a step s_[j] holds the OR over `cur` consecutive stored bits.
    const long m = (i1 - i0 + 1) + (run.len + 63) / 64 + 1;
    s_.resize(size_t(m));
    for (long j = 0; j < m; ++j) s_[j] = bitsAt(arow, n, 64L * (i0 + j) + run.c0);
    for (int cur = 1; cur < run.len;) {
      const int s = std::min(cur, run.len - cur);
      for (long j = 0; j < m; ++j) s_[j] |= bitsAt(s_.data(), m, 64L * j + s);
      cur += s;
    }
    for (int i = i0; i <= i1; ++i) e_[i - i0] = s_[i - i0];
  }

  void orBits(Word* row, int col, Word bits) const {
    if (col < 0) {
      if (col <= -64) return;
      bits >>= -col;
      col = 0;
    }
    const int w = col >> 6, sh = col & 63;
    if (w >= occ_.words) return;
    row[w] |= bits << sh;
    if (sh && w + 1 < occ_.words) row[w + 1] |= bits >> (64 - sh);
  }

  int longestFreeRun(const Word* row) const {
    const int W = occ_.width;
    int best = 0, cur = 0;
    for (int w = 0; w < occ_.words; ++w) {
      Word bits = row[w];
      const int nb = std::min(64, W - 64 * w);
      if (nb < 64) bits |= kAll << nb;
      if (bits == 0) {
        cur += 64;
        continue;
      }
      int pos = 0;
      while (pos < 64) {
        const Word rest = bits >> pos;
        if (rest == 0) {
          cur += 64 - pos;
          break;
        }
        const int z = __builtin_ctzll(rest);
        best = std::max(best, cur + z);
        cur = 0;
        pos += z;
        const Word ones = (~bits) >> pos;
        pos += ones == 0 ? 64 - pos : __builtin_ctzll(ones);
      }
    }
    return std::max(best, cur);
  }

  Bitmap occ_;
  std::vector<int> freeRun_;
  int usedW_ = 0, usedH_ = 0, firstOpen_ = 0;
  std::vector<Word> nonFull_;     // per row: bit w set when atlas word w has a free texel
  std::vector<Word> emptyWords_;  // per row: bit w set when atlas word w is wholly free
  int nfStride_ = 1;
  std::unordered_map<uint64_t, int> shapeStart_;  // footprint hash -> first row worth searching
  std::vector<Word> k_, e_, s_, live_;
};

// Width for an atlas that should take charts of this padded area: a square at the expected
// fill times `factor`, at least as wide as the narrowest orientation of the widest chart.
int atlasWidthFor(long long area, double factor, int minWidth, int maxSize) {
  const int w = roundUp4(int(std::ceil(factor * std::sqrt(double(area) / kExpectedFill))));
  return std::min(maxSize, std::max(w, minWidth));
}

struct Attempt {
  std::vector<glm::ivec2> atlasSizes;
  std::vector<ChartPlacement> placements;
  double area = 0.0;  // texels over all atlases
};

// One bottom-left packing of all charts in `order` into atlases of a given width factor.
// Stops after the first `limit` charts of `order` (a trial of the layout's big charts).
Attempt packAttempt(const std::vector<Prepared>& prep, const std::vector<size_t>& order,
                    const std::vector<long long>& areaFrom, double factor, int minWidth,
                    int padding, int maxSize, size_t limit,
                    const std::function<bool()>& cancelled) {
  Attempt attempt;
  attempt.placements.resize(prep.size());
  std::vector<Atlas> atlases;
  auto tryPlace = [&](int a, const Prepared& c, ChartPlacement& out) {
    Atlas& atlas = atlases[a];
    int bestX = 0, bestY = 0, bestV = -1, bestTop = 0;
    for (int vi = 0; vi < 2; ++vi) {
      const Variant& v = c.v[vi];
      if (!v.valid) continue;
      const int topLimit = bestV < 0 ? 1 << 30 : bestTop;  // a higher top can't win
      int x, y;
      if (!atlas.find(v, topLimit, x, y)) continue;
      const int top = y + v.rows;
      if (bestV < 0 || top < bestTop || (top == bestTop && (y < bestY || (y == bestY && x < bestX))))
        bestX = x, bestY = y, bestV = vi, bestTop = top;
    }
    if (bestV < 0) return false;
    const Variant& v = c.v[bestV];
    atlas.place(v, bestX, bestY, padding);
    out.atlas = a;
    out.rotation = v.rotation;
    out.offset = glm::vec2(glm::dvec2(bestX, bestY) + v.shift);
    return true;
  };
  for (size_t k = 0; k < std::min(limit, order.size()); ++k) {
    if (cancelled && k % 64 == 0 && cancelled()) break;
    const size_t i = order[k];
    ChartPlacement& out = attempt.placements[i];
    bool placed = false;
    for (int a = 0; a < int(atlases.size()) && !placed; ++a) placed = tryPlace(a, prep[i], out);
    if (!placed) {
      atlases.emplace_back(atlasWidthFor(areaFrom[k], factor, minWidth, maxSize), maxSize);
      if (!tryPlace(int(atlases.size()) - 1, prep[i], out)) {
        atlases.pop_back();  // cannot happen for a valid chart; keep the atlas list clean
        out = ChartPlacement();
      }
    }
  }
  for (const Atlas& atlas : atlases) {
    const glm::ivec2 size(std::min(maxSize, roundUp4(std::max(1, atlas.usedWidth()))),
                          std::min(maxSize, roundUp4(std::max(1, atlas.usedHeight()))));
    attempt.atlasSizes.push_back(size);
    attempt.area += double(size.x) * double(size.y);
  }
  if (limit < order.size() && !atlases.empty()) {
    // Predicted final area: the rest first fills the free space under the current top (at the
    // expected fill), then raises the top of the last atlas.
    const Atlas& last = atlases.back();
    const double freeBelow = double(last.width()) * last.usedHeight() - double(areaFrom[0] - areaFrom[limit]);
    const double rest = double(areaFrom[limit]) - kExpectedFill * std::max(0.0, freeBelow);
    attempt.area = double(last.width()) * last.usedHeight() + std::max(0.0, rest / kExpectedFill);
  }
  return attempt;
}

}  // namespace

PackResult packCharts(const std::vector<PackChart>& charts, const PackOptions& options) {
  PackResult result;
  const size_t n = charts.size();
  result.placements.resize(n);
  if (n == 0) return result;
  const int padding = std::max(0, options.padding);
  const int maxSize = std::max(4, options.maxAtlasSize);

  std::vector<Prepared> prep(n);
  parallelFor(n, [&](size_t i) {
    prepareChart(charts[i], padding, maxSize, options.allowRotation, prep[i]);
  });

  std::vector<size_t> order;
  order.reserve(n);
  for (size_t i = 0; i < n; ++i)
    if (prep[i].valid) order.push_back(i);
  std::stable_sort(order.begin(), order.end(),
                   [&](size_t a, size_t b) { return prep[a].sizeKey > prep[b].sizeKey; });

  // Remaining padded area from each position of `order` on, for sizing spill atlases.
  std::vector<long long> areaFrom(order.size() + 1, 0);
  int minWidth = 4;
  for (size_t k = order.size(); k-- > 0;) {
    const Prepared& c = prep[order[k]];
    areaFrom[k] = areaFrom[k + 1] + c.estArea;
    int narrow = maxSize + 1;
    for (const Variant& v : c.v)
      if (v.valid) narrow = std::min(narrow, v.cols);
    minWidth = std::max(minWidth, narrow);
  }

  // How well the last rows fill depends on the atlas width in a way no estimate predicts. The
  // big charts (most of the area, few of the charts) are packed at several widths and the best
  // predicted layouts are packed in full; the smallest total atlas area wins, ties going to the
  // earlier width, so the choice does not depend on the thread count.
  std::vector<double> factors;
  std::vector<int> firstWidths;
  for (double f : kWidthFactors) {
    const int w = atlasWidthFor(areaFrom[0], f, minWidth, maxSize);
    if (std::find(firstWidths.begin(), firstWidths.end(), w) != firstWidths.end()) continue;
    firstWidths.push_back(w);
    factors.push_back(f);
  }
  size_t bigCount = 0;
  while (bigCount < order.size() && areaFrom[0] - areaFrom[bigCount] < kBigShare * areaFrom[0])
    ++bigCount;
  if (factors.size() > kFullAttempts && bigCount < order.size()) {
    std::vector<double> trialArea(factors.size());
    parallelFor(
        factors.size(),
        [&](size_t a) {
          trialArea[a] = packAttempt(prep, order, areaFrom, factors[a], minWidth, padding,
                                     maxSize, bigCount, options.cancelled).area;
        },
        1);
    std::vector<size_t> rank(factors.size());
    std::iota(rank.begin(), rank.end(), size_t(0));
    std::stable_sort(rank.begin(), rank.end(),
                     [&](size_t a, size_t b) { return trialArea[a] < trialArea[b]; });
    rank.resize(kFullAttempts);
    std::sort(rank.begin(), rank.end());
    std::vector<double> kept;
    for (size_t a : rank) kept.push_back(factors[a]);
    factors = kept;
  }
  std::vector<Attempt> attempts(factors.size());
  parallelFor(
      factors.size(),
      [&](size_t a) {
        attempts[a] = packAttempt(prep, order, areaFrom, factors[a], minWidth, padding, maxSize,
                                  order.size(), options.cancelled);
      },
      1);
  size_t best = 0;
  for (size_t a = 1; a < attempts.size(); ++a)
    if (attempts[a].atlasSizes.size() < attempts[best].atlasSizes.size() ||
        (attempts[a].atlasSizes.size() == attempts[best].atlasSizes.size() &&
         attempts[a].area < attempts[best].area))
      best = a;
  result.atlasSizes = std::move(attempts[best].atlasSizes);
  result.placements = std::move(attempts[best].placements);
  return result;
}

}  // namespace afterglow::uv
