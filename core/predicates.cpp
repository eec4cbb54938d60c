// Exact orient2d / incircle: Shewchuk's stage-A filters, then a non-adaptive exact stage on the raw
// coordinates in expansion arithmetic (Shewchuk 1997, "Adaptive Precision Floating-Point Arithmetic and Fast
// Robust Geometric Predicates"). Products use Dekker/Veltkamp splitting, never fma, because
// shaders/predicates.glsl runs the same steps on devices whose fma is not fused. Keep the two files in step.
// Cost: the filter is a dozen flops; the exact incircle is a few thousand flops on expansions of at most 384
// components (about 1 us), taken only for (near-)co-circular inputs.
#include "core/predicates.hpp"

namespace cdtgpu::pred {
namespace {

// Unit roundoff of double, 2^-53.
constexpr double kEps = 1.0 / 9007199254740992.0;
// Filter bounds (Shewchuk): with differences, products and sums each rounded once (relative error <= eps
// per operation, no underflow/overflow in the documented range), the computed orient2d determinant is within
// (3 eps + 16 eps^2) * (|detleft| + |detright|) of the true one, and the incircle determinant within
// (10 eps + 96 eps^2) * permanent, where the permanent is the determinant's expansion with absolute values;
// the eps^2 terms also cover rounding of the bound's own product and sums. If |det| exceeds the bound, its
// sign is exact.
constexpr double kCcwErrBoundA = (3.0 + 16.0 * kEps) * kEps;
constexpr double kIccErrBoundA = (10.0 + 96.0 * kEps) * kEps;
// 2^27 + 1: splits a double into two 26-bit halves whose products are exact.
constexpr double kSplitter = 134217729.0;

inline int sign_of(double v) { return (v > 0.0) - (v < 0.0); }

// Knuth's TwoSum: x + y == a + b exactly.
inline void two_sum(double a, double b, double& x, double& y) {
  x = a + b;
  double bv = x - a;
  double av = x - bv;
  double br = b - bv;
  double ar = a - av;
  y = ar + br;
}

// Dekker's FastTwoSum, valid when |a| >= |b| (or a == 0).
inline void fast_two_sum(double a, double b, double& x, double& y) {
  x = a + b;
  double bv = x - a;
  y = b - bv;
}

inline void two_diff(double a, double b, double& x, double& y) {
  x = a - b;
  double bv = a - x;
  double av = x + bv;
  double br = bv - b;
  double ar = a - av;
  y = ar + br;
}

// Veltkamp split: a == hi + lo, each with at most 26 significant bits.
inline void split(double a, double& hi, double& lo) {
  double c = kSplitter * a;
  double abig = c - a;
  hi = c - abig;
  lo = a - hi;
}

// Dekker's product with b already split: x + y == a * b exactly.
inline void two_product_presplit(double a, double b, double bhi, double blo, double& x, double& y) {
  x = a * b;
  double ahi, alo;
  split(a, ahi, alo);
  double err1 = x - ahi * bhi;
  double err2 = err1 - alo * bhi;
  double err3 = err2 - ahi * blo;
  y = alo * blo - err3;
}

inline void two_product(double a, double b, double& x, double& y) {
  double bhi, blo;
  split(b, bhi, blo);
  two_product_presplit(a, b, bhi, blo, x, y);
}

// (a1 + a0) - (b1 + b0) as a nonoverlapping 4-component expansion x[0..3], smallest first.
inline void two_two_diff(double a1, double a0, double b1, double b0, double* x) {
  double i, j, k;
  two_diff(a0, b0, i, x[0]);
  two_sum(a1, i, j, k);
  double l;
  two_diff(k, b1, l, x[1]);
  two_sum(j, l, x[3], x[2]);
}

// a.x * b.y - b.x * a.y exactly, as 4 components.
inline void cross_exact(XY a, XY b, double* x) {
  double p1, p0, q1, q0;
  two_product(a.x, b.y, p1, p0);
  two_product(b.x, a.y, q1, q0);
  two_two_diff(p1, p0, q1, q0, x);
}

// h = e + f (Shewchuk's fast-expansion-sum with zero elimination; needs round-to-nearest-even, which IEEE
// doubles give on the CPU and on the GPU). Returns the length of h, at least 1. h must not overlap e or f.
// Shaped like the GLSL version, which avoids branches around stores (a zero is stored, then overwritten or
// left past the end). TwoSum in place of Shewchuk's first FastTwoSum, and a start from q = 0, give the same
// components: both transforms are error-free.
int expansion_sum(int elen, const double* e, int flen, const double* f, double* h) {
  double enow = e[0], fnow = f[0];
  int ei = 0, fi = 0, hi = 0;
  double q = 0.0;
  for (int n = 0; n < elen + flen; ++n) {
    bool take_e = fi >= flen || (ei < elen && ((fnow > enow) == (fnow > -enow)));
    double v = take_e ? enow : fnow;
    ei += take_e;
    fi += !take_e;
    enow = e[ei < elen - 1 ? ei : elen - 1];
    fnow = f[fi < flen - 1 ? fi : flen - 1];
    double hh;
    two_sum(q, v, q, hh);
    h[hi] = hh;
    hi += hh != 0.0;
  }
  h[hi] = q;
  hi += q != 0.0 || hi == 0;
  return hi;
}

// h = e * b (scale-expansion with zero elimination). Returns the length of h (<= 2 * elen), at least 1.
int scale_expansion(int elen, const double* e, double b, double* h) {
  double bhi, blo;
  split(b, bhi, blo);
  double q, hh;
  two_product_presplit(e[0], b, bhi, blo, q, hh);
  int hi = 0;
  h[hi] = hh;
  hi += hh != 0.0;
  for (int i = 1; i < elen; ++i) {
    double p1, p0, sum;
    two_product_presplit(e[i], b, bhi, blo, p1, p0);
    two_sum(q, p0, sum, hh);
    h[hi] = hh;
    hi += hh != 0.0;
    fast_two_sum(p1, sum, q, hh);
    h[hi] = hh;
    hi += hh != 0.0;
  }
  h[hi] = q;
  hi += q != 0.0 || hi == 0;
  return hi;
}

// The exact stages run as small programs over one scratch array, the same tables as in
// shaders/predicates.glsl: there every call site of a GLSL function is inlined, and one copy of each expansion
// routine per predicate (instead of forty) keeps lavapipe's LLVM compile time in seconds, not minutes.
// Expansion registers and their offsets in the scratch array (maximum lengths as in Shewchuk's incircleexact):
// 0-5 the cross products ab bc cd da ac bd (4 each), 6 an 8-term temp, 7-10 the 3x3 minors abc bcd cda dab
// (12), 11-14 a row scaled once / twice by x and by y (24, 48, 24, 48), 15-16 two rows' lifted terms (96),
// 17 rows a+b, 18 rows c+d (192), 19 the determinant (384, over registers 0-14, which are consumed by then).
constexpr int kScratch = 800;
constexpr int kRegisters = 20;
constexpr int kOffset[kRegisters] = {0, 4, 8, 12, 16, 20, 24, 32, 44, 56, 68, 80, 104, 152, 176, 224, 320, 416, 608, 0};

// One step: {opcode, a, b, dst}. kCross: dst = cross(point a, point b). kSum: dst = reg a + reg b.
// kScale: dst = reg a * coordinate b, with b = point * 4 + (y ? 2 : 0) + (negated ? 1 : 0). kNeg: reg a = -reg a.
enum Opcode { kCross = 0, kSum = 1, kScale = 2, kNeg = 3 };
struct Step {
  int op, a, b, dst;
};
constexpr int kOrientBegin = 0, kOrientEnd = 5, kIncircleBegin = 5, kIncircleEnd = 44;
constexpr Step kProgram[44] = {
    // orient2d(a, b, c) = cross(a, b) + cross(b, c) + cross(c, a)
    {kCross, 0, 1, 0}, {kCross, 1, 2, 1}, {kCross, 2, 0, 2}, {kSum, 0, 1, 6}, {kSum, 6, 2, 7},
    // incircle: the 4x4 determinant | x y x^2+y^2 1 | along the lift column (Shewchuk's incircleexact)
    {kCross, 0, 1, 0}, {kCross, 1, 2, 1}, {kCross, 2, 3, 2}, {kCross, 3, 0, 3}, {kCross, 0, 2, 4}, {kCross, 1, 3, 5},
    {kSum, 2, 3, 6}, {kSum, 6, 4, 9},    // cda = cd + da + ac
    {kSum, 3, 0, 6}, {kSum, 6, 5, 10},   // dab = da + ab + bd
    {kNeg, 5, 0, 5}, {kNeg, 4, 0, 4},
    {kSum, 0, 1, 6}, {kSum, 6, 4, 7},    // abc = ab + bc - ac
    {kSum, 1, 2, 6}, {kSum, 6, 5, 8},    // bcd = bc + cd - bd
    // + bcd |a|^2
    {kScale, 8, 0, 11}, {kScale, 11, 0, 12}, {kScale, 8, 2, 13}, {kScale, 13, 2, 14}, {kSum, 12, 14, 15},
    // - cda |b|^2
    {kScale, 9, 4, 11}, {kScale, 11, 5, 12}, {kScale, 9, 6, 13}, {kScale, 13, 7, 14}, {kSum, 12, 14, 16},
    {kSum, 15, 16, 17},
    // + dab |c|^2
    {kScale, 10, 8, 11}, {kScale, 11, 8, 12}, {kScale, 10, 10, 13}, {kScale, 13, 10, 14}, {kSum, 12, 14, 15},
    // - abc |d|^2
    {kScale, 7, 12, 11}, {kScale, 11, 13, 12}, {kScale, 7, 14, 13}, {kScale, 13, 15, 14}, {kSum, 12, 14, 16},
    {kSum, 15, 16, 18},
    {kSum, 17, 18, 19},
};

// Runs kProgram[begin, end) on the points and returns the sign of the last register written.
int run_exact(const XY* pt, int begin, int end) {
  double s[kScratch];
  int len[kRegisters] = {};
  int dst = 0;
  for (int i = begin; i < end; ++i) {
    const Step& st = kProgram[i];
    dst = st.dst;
    double* out = s + kOffset[dst];
    if (st.op == kCross) {
      cross_exact(pt[st.a], pt[st.b], out);
      len[dst] = 4;
    } else if (st.op == kSum) {
      len[dst] = expansion_sum(len[st.a], s + kOffset[st.a], len[st.b], s + kOffset[st.b], out);
    } else if (st.op == kScale) {
      const XY& p = pt[st.b >> 2];
      double v = (st.b & 2) ? p.y : p.x;
      if (st.b & 1) v = -v;
      len[dst] = scale_expansion(len[st.a], s + kOffset[st.a], v, out);
    } else {
      for (int k = 0; k < len[st.a]; ++k) out[k] = -out[k];
    }
  }
  return sign_of(s[kOffset[dst] + len[dst] - 1]);
}

}  // namespace

int orient2d_exact(XY a, XY b, XY c) {
  const XY pt[3] = {a, b, c};
  return run_exact(pt, kOrientBegin, kOrientEnd);
}

int orient2d(XY a, XY b, XY c) {
  double detleft = (a.x - c.x) * (b.y - c.y);
  double detright = (a.y - c.y) * (b.x - c.x);
  double det = detleft - detright;
  double detsum;
  // Opposite signs (or a zero) cannot cancel: the rounded difference has the exact sign.
  if (detleft > 0.0) {
    if (detright <= 0.0) return sign_of(det);
    detsum = detleft + detright;
  } else if (detleft < 0.0) {
    if (detright >= 0.0) return sign_of(det);
    detsum = -detleft - detright;
  } else {
    return sign_of(det);
  }
  double errbound = kCcwErrBoundA * detsum;
  if (det >= errbound || -det >= errbound) return sign_of(det);
  return orient2d_exact(a, b, c);
}

int incircle_exact(XY a, XY b, XY c, XY d) {
  const XY pt[4] = {a, b, c, d};
  return run_exact(pt, kIncircleBegin, kIncircleEnd);
}

int incircle(XY a, XY b, XY c, XY d) {
  double adx = a.x - d.x, bdx = b.x - d.x, cdx = c.x - d.x;
  double ady = a.y - d.y, bdy = b.y - d.y, cdy = c.y - d.y;

  double bdxcdy = bdx * cdy, cdxbdy = cdx * bdy;
  double alift = adx * adx + ady * ady;
  double cdxady = cdx * ady, adxcdy = adx * cdy;
  double blift = bdx * bdx + bdy * bdy;
  double adxbdy = adx * bdy, bdxady = bdx * ady;
  double clift = cdx * cdx + cdy * cdy;

  double det = alift * (bdxcdy - cdxbdy) + blift * (cdxady - adxcdy) + clift * (adxbdy - bdxady);
  double permanent = ((bdxcdy < 0 ? -bdxcdy : bdxcdy) + (cdxbdy < 0 ? -cdxbdy : cdxbdy)) * alift +
                     ((cdxady < 0 ? -cdxady : cdxady) + (adxcdy < 0 ? -adxcdy : adxcdy)) * blift +
                     ((adxbdy < 0 ? -adxbdy : adxbdy) + (bdxady < 0 ? -bdxady : bdxady)) * clift;
  double errbound = kIccErrBoundA * permanent;
  if (det > errbound || -det > errbound) return sign_of(det);
  return incircle_exact(a, b, c, d);
}

int incircle_perturbed(XY p0, XY p1, XY p2, XY p) {
  // Sort the four points by (x, y). CGAL uses std::sort on four pointers, which libstdc++ runs as an
  // insertion sort, so ties (equal points) keep their argument order: a stable insertion sort matches it.
  const XY pts[4] = {p0, p1, p2, p};
  int order[4] = {0, 1, 2, 3};
  for (int i = 1; i < 4; ++i) {
    int v = order[i];
    int j = i;
    while (j > 0) {
      const XY& u = pts[order[j - 1]];
      bool less = pts[v].x < u.x || (pts[v].x == u.x && pts[v].y < u.y);
      if (!less) break;
      order[j] = order[j - 1];
      --j;
    }
    order[j] = v;
  }
  // Step 0 asks incircle; when it is 0, steps 1-3 walk from the largest point down (never the smallest, as
  // in CGAL): the query point answers "outside"; point k of the triangle asks the orientation with p in
  // place of p_k (k == 2: (p0, p1, p); 1: (p0, p, p2); 0: (p, p1, p2)), and a non-zero one decides.
  for (int step = 0; step < 4; ++step) {
    int s;
    if (step == 0) {
      s = incircle(p0, p1, p2, p);
    } else {
      int k = order[4 - step];
      if (k == 3) return -1;
      s = orient2d(k == 0 ? p : p0, k == 1 ? p : p1, k == 2 ? p : p2);
    }
    if (s != 0) return s;
  }
  return -1;
}

}  // namespace cdtgpu::pred
