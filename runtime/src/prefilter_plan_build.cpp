// Building a PrefilterPlan's rows (prefilter_plan.h): the quadtree of chain texels each output
// texel's lobe is integrated over, the tent of the sharpest lobes, and the cube's symmetries
// that map one row per orbit to the others.
#include "afterglow/runtime/prefilter_plan.h"

#include <algorithm>
#include <cmath>
#include <utility>
#include <vector>

namespace afterglow::runtime {

namespace {

constexpr double kPiD = 3.14159265358979323846;
// How far Simpson's rule may stray from the midpoint rule over a coarse node, against the
// row's total.
constexpr double kNodeMass = 1e-2;
// How far f may bend across a source texel's tent, against the allowance of the header's
// error control, before the tent is integrated with sub-samples (the figures hardly move
// between 0.1 and 1).
constexpr double kTentBend = 0.3;
// Sub-samples per α of a tent's texel width (2 to 16 a side).
constexpr double kPartsPerAlpha = 4.0;

// The split sum's weight density D(n·h) (n·l)⁺ as a function of cos θ = n·l (n = v): with
// (n·h)² = (1 + cos θ)/2, D's denominator (n·h)²(α² − 1) + 1 is (1 − cos θ)/2 + α² (1 + cos θ)/2,
// which keeps its digits at the peak of a sharp lobe.
double lobeDensity(double cosTheta, double alpha) {
  if (cosTheta <= 0.0) return 0.0;
  const double a2 = alpha * alpha;
  const double d = 0.5 * (1.0 - cosTheta) + 0.5 * a2 * (1.0 + cosTheta);
  return a2 / (kPiD * d * d) * cosTheta;
}

// A face's plane: its point (a, b) ∈ [−1, 1]² is axis + a·u + b·v (cubemap.h's table with
// a = 2u − 1, b = 2v − 1), read back from cubemapDirection and rounded to the axis vectors it
// is made of, so that directions are computed in double.
struct PlaneFrame {
  glm::dvec3 axis, u, v;
};

PlaneFrame planeFrame(int face) {
  auto dir = [&](float u, float v) { return glm::dvec3(cubemapDirection(face, u, v)); };
  const glm::dvec3 axis = glm::round(dir(0.5f, 0.5f));
  return {axis, glm::round(std::sqrt(2.0) * dir(1.0f, 0.5f) - axis),
          glm::round(std::sqrt(2.0) * dir(0.5f, 1.0f) - axis)};
}

// A chain texel's geometry, the same on every face: its solid angle, the solid-angle-weighted
// centroid of its level-0 texels' centres in face-plane coordinates (the point its moments
// are taken about), and the sine of the largest angle from the centroid's direction to a
// corner.
struct NodeShape {
  double omega;
  glm::dvec2 centroid;
  double sinRadius;
};

// One of the cube's 48 symmetries (the signed permutations of the axes): it maps every face
// to a face and every texel of every level to a texel of that level, and a face's plane
// coordinates by a signed permutation: a' = m[0] a + m[1] b, b' = m[2] a + m[3] b.
struct Symmetry {
  int face[kCubeFaceCount];
  int m[kCubeFaceCount][4];
  int inverse;

  // Texel (x, y) of a face of `size` → the image's (x, y) (texel centres map to centres).
  void texel(int f, int size, int x, int y, int& xOut, int& yOut) const {
    const int* k = m[f];
    const int a = 2 * x + 1 - size, b = 2 * y + 1 - size;
    xOut = (k[0] * a + k[1] * b + size - 1) / 2;
    yOut = (k[2] * a + k[3] * b + size - 1) / 2;
  }
};

std::vector<Symmetry> cubeSymmetries(const PlaneFrame* frames) {
  std::vector<Symmetry> out;
  std::vector<glm::imat3x3> matrices;
  const int perms[6][3] = {{0, 1, 2}, {0, 2, 1}, {1, 0, 2}, {1, 2, 0}, {2, 0, 1}, {2, 1, 0}};
  for (const auto& p : perms)
    for (int signs = 0; signs < 8; ++signs) {
      glm::dmat3 P(0.0);
      for (int i = 0; i < 3; ++i) P[p[i]][i] = (signs >> i) & 1 ? -1.0 : 1.0;  // column p[i]
      Symmetry s{};
      for (int f = 0; f < kCubeFaceCount; ++f) {
        const glm::dvec3 axis = P * frames[f].axis;
        int g = 0;
        while (glm::dot(axis, frames[g].axis) < 0.5) ++g;
        s.face[f] = g;
        const glm::dvec3 u = P * frames[f].u, v = P * frames[f].v;
        s.m[f][0] = int(std::lround(glm::dot(u, frames[g].u)));
        s.m[f][1] = int(std::lround(glm::dot(v, frames[g].u)));
        s.m[f][2] = int(std::lround(glm::dot(u, frames[g].v)));
        s.m[f][3] = int(std::lround(glm::dot(v, frames[g].v)));
      }
      matrices.push_back(glm::imat3x3(P));
      out.push_back(s);
    }
  for (size_t i = 0; i < matrices.size(); ++i)
    for (size_t j = 0; j < matrices.size(); ++j)
      if (matrices[i] * matrices[j] == glm::imat3x3(1)) out[i].inverse = int(j);
  return out;
}

int log2Exact(int n) {
  int k = 0;
  while ((1 << k) < n) ++k;
  return k;
}

}  // namespace

// Everything the rows are built from, shared by the rows of all mips.
struct PrefilterPlan::Builder {
  const PrefilterPlan& plan;
  const PrefilterPlanOptions& options;
  int S = 0;
  int levels = 0;
  PlaneFrame frames[kCubeFaceCount];
  std::vector<std::vector<NodeShape>> shapes;

  // One row's accumulation: weights per scratch index.
  std::vector<double> acc;
  std::vector<uint8_t> used;
  std::vector<uint32_t> touched;
  std::vector<uint8_t> inTent, inScatter;
  std::vector<uint32_t> tent, scatter;
  std::vector<std::pair<double, uint32_t>> candidates;
  struct Pending {
    int level, face, x, y;
  };
  std::vector<Pending> stack;
  int totalMip = -1;
  double lobeTotal = 0.0;

  Builder(const PrefilterPlan& p, const PrefilterPlanOptions& o) : plan(p), options(o) {}

  glm::dvec3 direction(int face, double a, double b) const {
    const PlaneFrame& f = frames[face];
    return glm::normalize(f.axis + a * f.u + b * f.v);
  }

  void add(size_t index, double w) {
    if (w == 0.0) return;
    if (!used[index]) used[index] = 1, touched.push_back(uint32_t(index));
    acc[index] += w;
  }

  // The level-0 texel (x + dx, y + dy) of index's face, continued across its edges.
  uint32_t neighbour(uint32_t index, int dx, int dy) const {
    const int face = int(index) / (S * S);
    const int x = int(index) % S + dx;
    const int y = (int(index) / S) % S + dy;
    if (x >= 0 && x < S && y >= 0 && y < S) return uint32_t((face * S + y) * S + x);
    const CubeTexel t = cubemapTexel(
        cubemapDirection(face, (float(x) + 0.5f) / float(S), (float(y) + 0.5f) / float(S)), S);
    return uint32_t((t.face * S + t.y) * S + t.x);
  }

  std::vector<CubemapTap> row(int mip, int face, int ox, int oy);
};

std::vector<CubemapTap> PrefilterPlan::Builder::row(int mip, int face, int ox, int oy) {
  const int outSize = std::max(1, S >> mip);
  const double r = double(roughnessOfMip(float(mip), plan.mipCount_));
  const double alpha = r * r;
  const double peak = lobeDensity(1.0, alpha);
  const int sub = std::clamp(int(std::ceil(kPartsPerAlpha * (2.0 / S) / alpha)), 2, 16);
  const double partArea = (2.0 / double(S * sub)) * (2.0 / double(S * sub));
  // The row's total ∫ f dω, from θ alone (f is symmetric about n), by the midpoint rule in θ:
  // the same for every row of the mip.
  if (totalMip != mip) {
    const int steps = 20000;
    const double dt = 0.5 * kPiD / steps;
    lobeTotal = 0.0;
    for (int i = 0; i < steps; ++i) {
      const double t = (i + 0.5) * dt;
      lobeTotal += lobeDensity(std::cos(t), alpha) * std::sin(t);
    }
    lobeTotal *= 2.0 * kPiD * dt;
    totalMip = mip;
  }
  // Coarser mips have a quarter of the texels each: a tighter tolerance costs little there.
  const double tolerance =
      mip == 1 ? options.firstMipTolerance : options.tolerance * std::pow(0.5, mip - 2);
  const glm::dvec3 n =
      direction(face, (2.0 * ox + 1.0) / outSize - 1.0, (2.0 * oy + 1.0) / outSize - 1.0);

  for (int f = kCubeFaceCount - 1; f >= 0; --f) stack.push_back({levels - 1, f, 0, 0});
  while (!stack.empty()) {
    const Pending p = stack.back();
    stack.pop_back();
    const int size = S >> p.level;
    const size_t xy = size_t(p.y * size + p.x);
    const size_t index = size_t(p.face) * size_t(size) * size_t(size) + xy;
    const NodeShape& shape = shapes[size_t(p.level)][xy];
    const double cosCentre = glm::dot(n, direction(p.face, shape.centroid.x, shape.centroid.y));
    if (cosCentre <= -shape.sinRadius) continue;  // wholly below the horizon
    const double scale =
        std::sqrt(std::max(lobeDensity(cosCentre, alpha), options.floor * peak) * peak);
    const double allowed = tolerance * scale;
    // The lobe on a 3 × 3 grid of face-plane points around the node's centre, spaced by half
    // its width (level ≥ 1) or by one texel (level 0), with the solid-angle density
    // dω/dA = (1 + a² + b²)^(−3/2) at each.
    const double h = p.level > 0 ? 1.0 / size : 2.0 / size;
    const double a0 = (2.0 * p.x + 1.0) / size - 1.0, b0 = (2.0 * p.y + 1.0) / size - 1.0;
    double fq[3][3], jq[3][3];
    for (int j = 0; j < 3; ++j)
      for (int i = 0; i < 3; ++i) {
        const double a = a0 + (i - 1) * h, b = b0 + (j - 1) * h;
        const glm::dvec3 point = frames[p.face].axis + a * frames[p.face].u + b * frames[p.face].v;
        const double inverseLength = 1.0 / glm::length(point);
        fq[j][i] = lobeDensity(glm::dot(n, point) * inverseLength, alpha);
        jq[j][i] = inverseLength * inverseLength * inverseLength;
      }
    if (p.level > 0) {
      // ∫_node f dω by Simpson's rule, and f as its mean plus a linear term across the node
      // (central differences), which the node's moments integrate: accepted where that model
      // holds at the nine grid points and at the node's point nearest n.
      const double w[3] = {1.0, 4.0, 1.0};
      double integral = 0.0;
      for (int j = 0; j < 3; ++j)
        for (int i = 0; i < 3; ++i) integral += w[i] * w[j] * fq[j][i] * jq[j][i];
      integral *= (h / 3.0) * (h / 3.0);
      const double mean = integral / shape.omega;
      glm::dvec2 g(0.0);
      for (int k = 0; k < 3; ++k) {
        g.x += w[k] * (fq[k][2] - fq[k][0]);
        g.y += w[k] * (fq[2][k] - fq[0][k]);
      }
      g /= 6.0 * 2.0 * h;
      const glm::dvec2 c = shape.centroid;
      double worstLinear = 0.0, worstConstant = 0.0;
      bool negative = false;
      auto check = [&](glm::dvec2 q, double fAtQ) {
        const double linear = mean + glm::dot(g, q - c);
        negative = negative || linear < 0.0;
        worstLinear = std::max(worstLinear, std::abs(fAtQ - linear));
        worstConstant = std::max(worstConstant, std::abs(fAtQ - mean));
      };
      for (int j = 0; j < 3; ++j)
        for (int i = 0; i < 3; ++i) check(glm::dvec2(a0 + (i - 1) * h, b0 + (j - 1) * h), fq[j][i]);
      // The node's point nearest n, where f is largest: the grid may miss a lobe narrower
      // than the node.
      const PlaneFrame& frame = frames[p.face];
      const double along = glm::dot(n, frame.axis);
      if (along > 0.0) {
        const glm::dvec2 q(std::clamp(glm::dot(n, frame.u) / along, a0 - h, a0 + h),
                           std::clamp(glm::dot(n, frame.v) / along, b0 - h, b0 + h));
        check(q, lobeDensity(glm::dot(n, direction(p.face, q.x, q.y)), alpha));
      }
      // The constant model costs one tap, the linear three. And Simpson's rule must agree with
      // the midpoint rule: one of its samples near a peak narrower than the node would weigh
      // the node far beyond its share of the row.
      const double midpoint = fq[1][1] * jq[1][1] * 4.0 * h * h;
      bool accept = std::abs(integral - midpoint) <= kNodeMass * lobeTotal;
      if (accept && worstConstant <= allowed)
        g = glm::dvec2(0.0);
      else
        accept = accept && !negative && worstLinear <= allowed;
      if (accept) {
        const size_t slot = plan.levelOffset_[size_t(p.level)] + 3 * index;
        add(slot, integral);
        if (g.x != 0.0 || g.y != 0.0) {
          add(slot + 1, g.x * shape.omega);
          add(slot + 2, g.y * shape.omega);
        }
      } else {
        for (int j = 1; j >= 0; --j)
          for (int i = 1; i >= 0; --i)
            stack.push_back({p.level - 1, p.face, 2 * p.x + i, 2 * p.y + j});
      }
    } else {
      // A source texel read bilinearly weighs ∫ f · tent: exact for f quadratic over the
      // tent's support with (1, 10, 1)/12 per axis at the neighbours' centres. Where f bends
      // more than that (the peak of a lobe a few texels wide) the tent is integrated with
      // sub-samples instead.
      double bend = std::abs(fq[1][0] - 2.0 * fq[1][1] + fq[1][2]) +
                    std::abs(fq[0][1] - 2.0 * fq[1][1] + fq[2][1]);
      // A lobe narrower than a texel can peak between the samples: compare f where the
      // support comes nearest n with the biquadratic through the nine samples there.
      const PlaneFrame& frame = frames[p.face];
      const double along = glm::dot(n, frame.axis);
      if (along > 0.0) {
        const double tx = std::clamp((glm::dot(n, frame.u) / along - a0) / h, -1.0, 1.0);
        const double ty = std::clamp((glm::dot(n, frame.v) / along - b0) / h, -1.0, 1.0);
        const double lx[3] = {0.5 * tx * (tx - 1.0), 1.0 - tx * tx, 0.5 * tx * (tx + 1.0)};
        const double ly[3] = {0.5 * ty * (ty - 1.0), 1.0 - ty * ty, 0.5 * ty * (ty + 1.0)};
        double quadratic = 0.0;
        for (int j = 0; j < 3; ++j)
          for (int i = 0; i < 3; ++i) quadratic += lx[i] * ly[j] * fq[j][i];
        const double f =
            lobeDensity(glm::dot(n, direction(p.face, a0 + tx * h, b0 + ty * h)), alpha);
        bend = std::max(bend, std::abs(f - quadratic));
      }
      if (bend <= kTentBend * scale) {
        const double w[3] = {1.0, 10.0, 1.0};
        double integral = 0.0;
        for (int j = 0; j < 3; ++j)
          for (int i = 0; i < 3; ++i) integral += w[i] * w[j] * fq[j][i] * jq[j][i];
        add(index, integral * (h / 12.0) * (h / 12.0));
      } else {
        inTent[index] = 1;
        tent.push_back(uint32_t(index));
      }
    }
  }

  // The tent texels' weights: every sub-sample of them and of the texels around them (whose
  // bilinear reads reach into them) spread by sampleCubemap's weights, kept where they land
  // on a tent texel.
  for (uint32_t t : tent) {
    const int x = int(t) % S, y = (int(t) / S) % S;
    const int reach = std::min(std::min(x, S - 1 - x), std::min(y, S - 1 - y)) < 2 ? 2 : 1;
    for (int dy = -reach; dy <= reach; ++dy)
      for (int dx = -reach; dx <= reach; ++dx) {
        const uint32_t b = neighbour(t, dx, dy);
        if (!inScatter[b]) inScatter[b] = 1, scatter.push_back(b);
      }
  }
  for (uint32_t b : scatter) {
    const int bface = int(b) / (S * S), bx = int(b) % S, by = (int(b) / S) % S;
    const bool interior = bx >= 1 && bx <= S - 2 && by >= 1 && by <= S - 2;
    for (int j = 0; j < sub; ++j)
      for (int i = 0; i < sub; ++i) {
        const double a = 2.0 * (bx + (i + 0.5) / sub) / S - 1.0;
        const double bb = 2.0 * (by + (j + 0.5) / sub) / S - 1.0;
        const glm::dvec3 point = frames[bface].axis + a * frames[bface].u + bb * frames[bface].v;
        const double inverseLength = 1.0 / glm::length(point);
        const double w = lobeDensity(glm::dot(n, point) * inverseLength, alpha) * partArea *
                         inverseLength * inverseLength * inverseLength;
        if (!(w > 0.0)) continue;
        if (interior) {
          // Inside the face: the four texel centres around the sub-sample.
          const double fx = bx + (i + 0.5) / sub - 0.5, fy = by + (j + 0.5) / sub - 0.5;
          const int x0 = int(std::floor(fx)), y0 = int(std::floor(fy));
          const double wx = fx - x0, wy = fy - y0;
          const uint32_t base = uint32_t((bface * S + y0) * S + x0);
          const uint32_t idx[4] = {base, base + 1, base + uint32_t(S), base + uint32_t(S) + 1};
          const double bw[4] = {(1 - wx) * (1 - wy), wx * (1 - wy), (1 - wx) * wy, wx * wy};
          for (int k = 0; k < 4; ++k)
            if (inTent[idx[k]]) add(idx[k], w * bw[k]);
        } else {
          CubemapTap taps[kMaxCubemapTaps];
          const int count = cubemapBilinearTaps(S, glm::vec3(point * inverseLength), taps);
          for (int k = 0; k < count; ++k)
            if (inTent[taps[k].index]) add(taps[k].index, w * double(taps[k].weight));
        }
      }
    inScatter[b] = 0;
  }
  for (uint32_t t : tent) inTent[t] = 0;
  tent.clear();
  scatter.clear();

  // Drop the taps that can move the output least, up to options.dropBelow of the row's total
  // between them: a radiance weight can move it by its weight times the largest radiance, a
  // moment weight by its weight times the node's half-width.
  double total = 0.0;
  candidates.clear();
  for (uint32_t i : touched) {
    double reach = std::abs(acc[i]);
    int level = 0;
    if (plan.isRadiance(i, &level))
      total += acc[i];
    else
      reach *= 1.0 / double(S >> level);
    candidates.push_back({reach, i});
  }
  std::sort(candidates.begin(), candidates.end());
  double dropped = 0.0, droppedWeight = 0.0;
  for (const std::pair<double, uint32_t>& c : candidates) {
    if (dropped + c.first > options.dropBelow * total) break;
    dropped += c.first;
    if (plan.isRadiance(c.second)) droppedWeight += acc[c.second];
    acc[c.second] = 0.0;
  }
  std::sort(touched.begin(), touched.end());
  const double kept = total - droppedWeight;
  std::vector<CubemapTap> out;
  for (uint32_t i : touched) {
    if (acc[i] != 0.0) out.push_back({i, float(acc[i] / kept)});
    acc[i] = 0.0;
    used[i] = 0;
  }
  touched.clear();
  return out;
}

PrefilterPlan PrefilterPlan::build(int sourceSize, int mipCount,
                                   const PrefilterPlanOptions& options) {
  PrefilterPlan plan;
  if (!supports(sourceSize) || mipCount < 1) return plan;
  plan.sourceSize_ = sourceSize;
  plan.mipCount_ = mipCount;
  Builder builder(plan, options);
  const int S = builder.S = sourceSize;
  const int levels = builder.levels = log2Exact(S) + 1;  // S, S/2, ..., 1
  for (int face = 0; face < kCubeFaceCount; ++face) builder.frames[face] = planeFrame(face);

  // Geometry per level (the same on every face), and the scratch layout: every level's C,
  // then levels ≥ 1's X and Y.
  std::vector<std::vector<NodeShape>>& shapes = builder.shapes;
  shapes.resize(size_t(levels));
  for (int k = 0; k < levels; ++k) {
    const int n = S >> k;
    std::vector<NodeShape>& level = shapes[size_t(k)];
    level.resize(size_t(n) * size_t(n));
    for (int y = 0; y < n; ++y)
      for (int x = 0; x < n; ++x) {
        NodeShape& s = level[size_t(y * n + x)];
        if (k == 0) {
          s.omega = double(cubemapTexelSolidAngle(x, y, n));
          s.centroid = {(2.0 * x + 1.0) / n - 1.0, (2.0 * y + 1.0) / n - 1.0};
        } else {
          // The exact partition: the children's sums.
          s.omega = 0.0;
          s.centroid = glm::dvec2(0.0);
          for (int j = 0; j < 2; ++j)
            for (int i = 0; i < 2; ++i) {
              const NodeShape& c = shapes[size_t(k - 1)][size_t((2 * y + j) * 2 * n + 2 * x + i)];
              s.centroid += c.omega * c.centroid;
              s.omega += c.omega;
            }
          s.centroid /= s.omega;
        }
        const glm::dvec3 d = builder.direction(0, s.centroid.x, s.centroid.y);
        double cosRadius = 1.0;
        for (int j = 0; j < 2; ++j)
          for (int i = 0; i < 2; ++i)
            cosRadius =
                std::min(cosRadius, glm::dot(d, builder.direction(0, 2.0 * (x + i) / n - 1.0,
                                                                  2.0 * (y + j) / n - 1.0)));
        s.sinRadius = std::sqrt(std::max(0.0, 1.0 - cosRadius * cosRadius));
      }
  }
  // Level 0's texels, then each coarser level's texels as triplets: radiance, moment along a,
  // moment along b (read together by a linear tap).
  plan.levelOffset_.push_back(0);
  for (int k = 0; k < levels; ++k)
    plan.levelOffset_.push_back(plan.levelOffset_.back() + (k == 0 ? 1 : 3) *
                                                               size_t(kCubeFaceCount) *
                                                               shapes[size_t(k)].size());
  plan.scratchSize_ = plan.levelOffset_.back();
  for (int k = 0; k + 1 < levels; ++k) {
    const int n = S >> k;
    std::vector<Child> c(size_t(n) * size_t(n));
    for (int y = 0; y < n; ++y)
      for (int x = 0; x < n; ++x) {
        const NodeShape& child = shapes[size_t(k)][size_t(y * n + x)];
        const NodeShape& parent = shapes[size_t(k + 1)][size_t((y / 2) * (n / 2) + x / 2)];
        c[size_t(y * n + x)] = {float(child.omega / parent.omega),
                                float(child.centroid.x - parent.centroid.x),
                                float(child.centroid.y - parent.centroid.y)};
      }
    plan.children_.push_back(std::move(c));
  }

  builder.acc.assign(plan.scratchSize_, 0.0);
  builder.used.assign(plan.scratchSize_, 0);
  builder.inTent.assign(plan.levelOffset_[1], 0);
  builder.inScatter.assign(plan.levelOffset_[1], 0);

  // Decoding a scratch index: its level, what it holds (0 C, 1 X, 2 Y), face, x, y.
  struct Place {
    int level, kind, face, x, y;
  };
  auto decode = [&](uint32_t i) {
    Place p{};
    plan.isRadiance(i, &p.level);
    size_t rel = i - plan.levelOffset_[size_t(p.level)];
    if (p.level > 0) p.kind = int(rel % 3), rel /= 3;
    const int n = S >> p.level;
    p.face = int(rel) / (n * n);
    p.y = (int(rel) / n) % n;
    p.x = int(rel) % n;
    return p;
  };
  auto encode = [&](const Place& p) {
    const int n = S >> p.level;
    const size_t texel = size_t((p.face * n + p.y) * n + p.x);
    return uint32_t(plan.levelOffset_[size_t(p.level)] +
                    (p.level > 0 ? 3 * texel + size_t(p.kind) : texel));
  };

  // Rows related by a symmetry of the cube have the same weights on related texels: each
  // orbit's first row is built, the others are its image.
  const std::vector<Symmetry> symmetries = cubeSymmetries(builder.frames);
  plan.mipRowBase_.assign(size_t(mipCount) + 1, 0);
  std::vector<CubemapTap> mapped;
  for (int m = 1; m < mipCount; ++m) {
    plan.mipRowBase_[size_t(m)] = plan.rows_.size();
    const int outSize = std::max(1, S >> m);
    const int rows = kCubeFaceCount * outSize * outSize;
    std::vector<std::vector<CubemapTap>> built{size_t(rows)};
    for (int t = 0; t < rows; ++t) {
      const int face = t / (outSize * outSize), y = (t / outSize) % outSize, x = t % outSize;
      // The orbit's first row c and a symmetry taking c to t.
      int canonical = t, to = -1;
      for (size_t g = 0; g < symmetries.size(); ++g) {
        int gx, gy;
        symmetries[g].texel(face, outSize, x, y, gx, gy);
        const int image = (symmetries[g].face[face] * outSize + gy) * outSize + gx;
        if (image < canonical) canonical = image, to = symmetries[g].inverse;
      }
      if (to < 0) {
        built[size_t(t)] = builder.row(m, face, x, y);
        plan.append(built[size_t(t)]);
      } else {
        const Symmetry& s = symmetries[size_t(to)];
        mapped.clear();
        for (const CubemapTap& tap : built[size_t(canonical)]) {
          Place p = decode(tap.index);
          const int* k = s.m[p.face];
          float weight = tap.weight;
          // A moment's weight is a plane vector's component: X → m[0] X' + m[2] Y',
          // Y → m[1] X' + m[3] Y', one of each pair 0 and the other ±1.
          if (p.kind == 1)
            p.kind = k[0] != 0 ? 1 : 2, weight *= float(k[0] != 0 ? k[0] : k[2]);
          else if (p.kind == 2)
            p.kind = k[1] != 0 ? 1 : 2, weight *= float(k[1] != 0 ? k[1] : k[3]);
          const int n = S >> p.level;
          int x2, y2;
          s.texel(p.face, n, p.x, p.y, x2, y2);
          p.face = s.face[p.face];
          p.x = x2;
          p.y = y2;
          mapped.push_back({encode(p), weight});
        }
        std::sort(mapped.begin(), mapped.end(),
                  [](const CubemapTap& a, const CubemapTap& b) { return a.index < b.index; });
        plan.append(mapped);
      }
    }
  }
  plan.mipRowBase_[size_t(mipCount)] = plan.rows_.size();
  Row pastTheEnd{};
  pastTheEnd.tap = uint32_t(plan.packed_.size());
  pastTheEnd.linear = uint32_t(plan.linear_.size());
  pastTheEnd.escape = uint32_t(plan.escapes_.size());
  plan.rows_.push_back(pastTheEnd);
  return plan;
}

}  // namespace afterglow::runtime
