// Exact-sign orient2d, incircle and CGAL's perturbed incircle for compute shaders: the same steps, in the same
// order, as core/predicates.cpp (see there and core/predicates.hpp for the filter bounds and the range of
// exactness). Every arithmetic double is `precise` (the SPIR-V has NoContraction on every FAdd, FSub, FMul),
// so no compiler fuses a*b+c into an fma (not fused on lavapipe) or rewrites the error-free transforms
// ((a+b)-a is not b). Needs shaderFloat64.
//
// The exact stages run as small programs (the same table as core/predicates.cpp) over one private scratch
// array addressed by offsets (GLSL has no pointers). Mesa inlines every call site, so the one copy of each
// expansion routine per predicate call keeps lavapipe's LLVM compile time in seconds; a straight-line version
// took minutes. Registers and maximum lengths, as in Shewchuk's incircleexact: the six 2x2 cross products (4
// each), an 8-term temp, the four 3x3 minors (12), a row scaled once / twice by x and by y (24, 48, 24, 48),
// two rows' lifted terms (96), rows a+b and c+d (192), the determinant (384, over registers that are consumed
// by then). 800 doubles (6.4 KB) per invocation, touched only by inputs the filters cannot decide.
#ifndef CDTGPU_PREDICATES_GLSL
#define CDTGPU_PREDICATES_GLSL

#define PRED_SCRATCH 800
double pred_s[PRED_SCRATCH];

const double PRED_EPS = 1.0lf / 9007199254740992.0lf;  // 2^-53
const double PRED_CCW_ERRBOUND_A = (3.0lf + 16.0lf * PRED_EPS) * PRED_EPS;
const double PRED_ICC_ERRBOUND_A = (10.0lf + 96.0lf * PRED_EPS) * PRED_EPS;
const double PRED_SPLITTER = 134217729.0lf;  // 2^27 + 1

int pred_sign(double v) { return int(v > 0.0lf) - int(v < 0.0lf); }

void pred_two_sum(double a, double b, out double x, out double y) {
  precise double s = a + b;
  precise double bv = s - a;
  precise double av = s - bv;
  precise double br = b - bv;
  precise double ar = a - av;
  precise double e = ar + br;
  x = s;
  y = e;
}

void pred_fast_two_sum(double a, double b, out double x, out double y) {
  precise double s = a + b;
  precise double bv = s - a;
  precise double e = b - bv;
  x = s;
  y = e;
}

void pred_two_diff(double a, double b, out double x, out double y) {
  precise double s = a - b;
  precise double bv = a - s;
  precise double av = s + bv;
  precise double br = bv - b;
  precise double ar = a - av;
  precise double e = ar + br;
  x = s;
  y = e;
}

void pred_split(double a, out double hi, out double lo) {
  precise double c = PRED_SPLITTER * a;
  precise double abig = c - a;
  precise double h = c - abig;
  precise double l = a - h;
  hi = h;
  lo = l;
}

void pred_two_product_presplit(double a, double b, double bhi, double blo, out double x, out double y) {
  precise double p = a * b;
  double ahi, alo;
  pred_split(a, ahi, alo);
  precise double err1 = p - ahi * bhi;
  precise double err2 = err1 - alo * bhi;
  precise double err3 = err2 - ahi * blo;
  precise double e = alo * blo - err3;
  x = p;
  y = e;
}

void pred_two_product(double a, double b, out double x, out double y) {
  double bhi, blo;
  pred_split(b, bhi, blo);
  pred_two_product_presplit(a, b, bhi, blo, x, y);
}

// (a1 + a0) - (b1 + b0) into pred_s[h .. h+4), smallest first.
void pred_two_two_diff(double a1, double a0, double b1, double b0, int h) {
  double i, j, k, l, x0, x1, x2, x3;
  pred_two_diff(a0, b0, i, x0);
  pred_two_sum(a1, i, j, k);
  pred_two_diff(k, b1, l, x1);
  pred_two_sum(j, l, x3, x2);
  pred_s[h] = x0;
  pred_s[h + 1] = x1;
  pred_s[h + 2] = x2;
  pred_s[h + 3] = x3;
}

// a.x * b.y - b.x * a.y into pred_s[h .. h+4).
void pred_cross_exact(dvec2 a, dvec2 b, int h) {
  double p1, p0, q1, q0;
  pred_two_product(a.x, b.y, p1, p0);
  pred_two_product(b.x, a.y, q1, q0);
  pred_two_two_diff(p1, p0, q1, q0, h);
}

// pred_s[h..) = pred_s[e .. e+elen) + pred_s[f .. f+flen) (Shewchuk's fast-expansion-sum with zero
// elimination; needs round-to-nearest-even). h must not overlap e or f. Returns the length, at least 1.
// Written without branches around stores (a zero is stored and then overwritten or left past the end): fewer
// basic blocks, which is what lavapipe's compile time grows with. TwoSum in place of Shewchuk's first
// FastTwoSum, and a start from q = 0, give the same components: both transforms are error-free.
int pred_expansion_sum(int e, int elen, int f, int flen, int h) {
  precise double enow = pred_s[e];
  precise double fnow = pred_s[f];
  int ei = 0, fi = 0, hi = 0;
  precise double q = 0.0lf;
  for (int n = 0; n < elen + flen; ++n) {
    bool take_e = fi >= flen || (ei < elen && ((fnow > enow) == (fnow > -enow)));
    precise double v = take_e ? enow : fnow;
    ei += int(take_e);
    fi += int(!take_e);
    enow = pred_s[e + min(ei, elen - 1)];
    fnow = pred_s[f + min(fi, flen - 1)];
    double qnew, hh;
    pred_two_sum(q, v, qnew, hh);
    q = qnew;
    pred_s[h + hi] = hh;
    hi += int(hh != 0.0lf);
  }
  pred_s[h + hi] = q;
  hi += int(q != 0.0lf || hi == 0);
  return hi;
}

// pred_s[h..) = pred_s[e .. e+elen) * b (scale-expansion with zero elimination); h must not overlap e.
// Returns the length (<= 2 elen), at least 1.
int pred_scale_expansion(int e, int elen, double b, int h) {
  double bhi, blo;
  pred_split(b, bhi, blo);
  double q, hh;
  pred_two_product_presplit(pred_s[e], b, bhi, blo, q, hh);
  int hi = 0;
  pred_s[h] = hh;
  hi += int(hh != 0.0lf);
  for (int i = 1; i < elen; ++i) {
    double p1, p0, sum;
    pred_two_product_presplit(pred_s[e + i], b, bhi, blo, p1, p0);
    pred_two_sum(q, p0, sum, hh);
    pred_s[h + hi] = hh;
    hi += int(hh != 0.0lf);
    pred_fast_two_sum(p1, sum, q, hh);
    pred_s[h + hi] = hh;
    hi += int(hh != 0.0lf);
  }
  pred_s[h + hi] = q;
  hi += int(q != 0.0lf || hi == 0);
  return hi;
}

#define PRED_REGISTERS 20
// (register 12 also holds kind 2's sum of three orientations: 36 terms at most)
const int PRED_OFFSET[PRED_REGISTERS] =
    int[PRED_REGISTERS](0, 4, 8, 12, 16, 20, 24, 32, 44, 56, 68, 80, 104, 152, 176, 224, 320, 416, 608, 0);

// Steps {opcode, a, b, dst}: 0 cross: dst = cross(point a, point b); 1 sum: dst = reg a + reg b; 2 scale:
// dst = reg a * coordinate b, b = point * 4 + (y ? 2 : 0) + (negated ? 1 : 0); 3 neg: reg a = -reg a.
// [0, 5): orient2d = cross(a,b) + cross(b,c) + cross(c,a). [5, 44): incircle, the 4x4 determinant
// | x y x^2+y^2 1 | along the lift column. [44, 61): orient2d(c0, x, q) + orient2d(c1, x, q) + orient2d(c2, x, q)
// for points c0, c1, c2, x, q = the sum of cross(c_k, x), of cross(q, c_k) and three times cross(x, q).
const ivec4 PRED_PROGRAM[61] = ivec4[61](
    ivec4(0, 0, 1, 0), ivec4(0, 1, 2, 1), ivec4(0, 2, 0, 2), ivec4(1, 0, 1, 6), ivec4(1, 6, 2, 7),
    ivec4(0, 0, 1, 0), ivec4(0, 1, 2, 1), ivec4(0, 2, 3, 2), ivec4(0, 3, 0, 3), ivec4(0, 0, 2, 4), ivec4(0, 1, 3, 5),
    ivec4(1, 2, 3, 6), ivec4(1, 6, 4, 9),
    ivec4(1, 3, 0, 6), ivec4(1, 6, 5, 10),
    ivec4(3, 5, 0, 5), ivec4(3, 4, 0, 4),
    ivec4(1, 0, 1, 6), ivec4(1, 6, 4, 7),
    ivec4(1, 1, 2, 6), ivec4(1, 6, 5, 8),
    ivec4(2, 8, 0, 11), ivec4(2, 11, 0, 12), ivec4(2, 8, 2, 13), ivec4(2, 13, 2, 14), ivec4(1, 12, 14, 15),
    ivec4(2, 9, 4, 11), ivec4(2, 11, 5, 12), ivec4(2, 9, 6, 13), ivec4(2, 13, 7, 14), ivec4(1, 12, 14, 16),
    ivec4(1, 15, 16, 17),
    ivec4(2, 10, 8, 11), ivec4(2, 11, 8, 12), ivec4(2, 10, 10, 13), ivec4(2, 13, 10, 14), ivec4(1, 12, 14, 15),
    ivec4(2, 7, 12, 11), ivec4(2, 11, 13, 12), ivec4(2, 7, 14, 13), ivec4(2, 13, 15, 14), ivec4(1, 12, 14, 16),
    ivec4(1, 15, 16, 18),
    ivec4(1, 17, 18, 19),
    ivec4(0, 0, 3, 0), ivec4(0, 1, 3, 1), ivec4(0, 2, 3, 2), ivec4(1, 0, 1, 6), ivec4(1, 6, 2, 7),
    ivec4(0, 4, 0, 0), ivec4(0, 4, 1, 1), ivec4(0, 4, 2, 2), ivec4(1, 0, 1, 6), ivec4(1, 6, 2, 8),
    ivec4(0, 3, 4, 0), ivec4(0, 3, 4, 1), ivec4(0, 3, 4, 2), ivec4(1, 0, 1, 6), ivec4(1, 6, 2, 9),
    ivec4(1, 7, 8, 11), ivec4(1, 11, 9, 12));

dvec2 pred_pt[5];
int pred_len[PRED_REGISTERS];

// Runs PRED_PROGRAM[begin, end) on pred_pt and returns the sign of the last register written.
int pred_run_exact(int begin, int end) {
  int dst = 0;
  for (int i = begin; i < end; ++i) {
    ivec4 st = PRED_PROGRAM[i];
    dst = st.w;
    int out_ = PRED_OFFSET[dst];
    if (st.x == 0) {
      pred_cross_exact(pred_pt[st.y], pred_pt[st.z], out_);
      pred_len[dst] = 4;
    } else if (st.x == 1) {
      pred_len[dst] = pred_expansion_sum(PRED_OFFSET[st.y], pred_len[st.y], PRED_OFFSET[st.z], pred_len[st.z], out_);
    } else if (st.x == 2) {
      dvec2 p = pred_pt[st.z >> 2];
      double v = (st.z & 2) != 0 ? p.y : p.x;
      if ((st.z & 1) != 0) v = -v;
      pred_len[dst] = pred_scale_expansion(PRED_OFFSET[st.y], pred_len[st.y], v, out_);
    } else {
      for (int k = 0; k < pred_len[st.y]; ++k) pred_s[out_ + k] = -pred_s[out_ + k];
    }
  }
  return pred_sign(pred_s[PRED_OFFSET[dst] + pred_len[dst] - 1]);
}

// Filters: the sign when the floating-point determinant's error bound decides it, else PRED_UNDECIDED.
#define PRED_UNDECIDED 2

int pred_orient2d_filter(dvec2 a, dvec2 b, dvec2 c) {
  precise double detleft = (a.x - c.x) * (b.y - c.y);
  precise double detright = (a.y - c.y) * (b.x - c.x);
  precise double det = detleft - detright;
  precise double detsum;
  if (detleft > 0.0lf) {
    if (detright <= 0.0lf) return pred_sign(det);
    detsum = detleft + detright;
  } else if (detleft < 0.0lf) {
    if (detright >= 0.0lf) return pred_sign(det);
    detsum = -detleft - detright;
  } else {
    return pred_sign(det);
  }
  precise double errbound = PRED_CCW_ERRBOUND_A * detsum;
  if (det >= errbound || -det >= errbound) return pred_sign(det);
  return PRED_UNDECIDED;
}

int pred_incircle_filter(dvec2 a, dvec2 b, dvec2 c, dvec2 d) {
  precise double adx = a.x - d.x, bdx = b.x - d.x, cdx = c.x - d.x;
  precise double ady = a.y - d.y, bdy = b.y - d.y, cdy = c.y - d.y;

  precise double bdxcdy = bdx * cdy, cdxbdy = cdx * bdy;
  precise double alift = adx * adx + ady * ady;
  precise double cdxady = cdx * ady, adxcdy = adx * cdy;
  precise double blift = bdx * bdx + bdy * bdy;
  precise double adxbdy = adx * bdy, bdxady = bdx * ady;
  precise double clift = cdx * cdx + cdy * cdy;

  precise double det = alift * (bdxcdy - cdxbdy) + blift * (cdxady - adxcdy) + clift * (adxbdy - bdxady);
  precise double permanent = (abs(bdxcdy) + abs(cdxbdy)) * alift + (abs(cdxady) + abs(adxcdy)) * blift +
                             (abs(adxbdy) + abs(bdxady)) * clift;
  precise double errbound = PRED_ICC_ERRBOUND_A * permanent;
  if (det > errbound || -det > errbound) return pred_sign(det);
  return PRED_UNDECIDED;
}

#ifdef PRED_CORNER
// Kind 2, for shaders that define PRED_CORNER(k) (k = 0, 1, 2) before including this file: the sign of
// orient2d(c0, x, q) + orient2d(c1, x, q) + orient2d(c2, x, q), c_k = PRED_CORNER(k), which is that of
// orient2d(centroid, x, q), exactly, with no rounded centroid; here when the rounding bound decides it: each
// determinant as in pred_orient2d_filter (error below 3.0000001 eps times its |left| + |right|), plus two
// additions (2 eps of the same sum, loosely): 8 eps is safe.
int pred_orient_sum_filter(dvec2 x, dvec2 q) {
  precise double det = 0.0lf, sum = 0.0lf;
  for (int k = 0; k < 3; ++k) {
    dvec2 c = PRED_CORNER(k);
    precise double l = (c.x - q.x) * (x.y - q.y);
    precise double r = (c.y - q.y) * (x.x - q.x);
    det += l - r;
    sum += abs(l) + abs(r);
  }
  if (abs(det) > 8.0lf * PRED_EPS * sum) return pred_sign(det);
  return PRED_UNDECIDED;
}
#endif

// The one function that holds an exact stage: kind 0 is orient2d(a, b, c), kind 1 incircle(a, b, c, d),
// kind 2 the orientation sum of pred_orient_sum_filter with x = a, q = b.
// Each call site of it costs lavapipe 1-4 s of LLVM time (measured; once per machine, Mesa caches compiled
// shaders), so shaders should reach it, directly or through the wrappers below, from as few places as they can.
// The filter of a kind (see pred_sign_of): the sign, or PRED_UNDECIDED.
int pred_filter(int kind, dvec2 a, dvec2 b, dvec2 c, dvec2 d) {
#ifdef PRED_CORNER
  if (kind == 2) return pred_orient_sum_filter(a, b);
#endif
  return kind == 0 ? pred_orient2d_filter(a, b, c) : pred_incircle_filter(a, b, c, d);
}

int pred_sign_of(int kind, dvec2 a, dvec2 b, dvec2 c, dvec2 d) {
  int s = pred_filter(kind, a, b, c, d);
  if (s != PRED_UNDECIDED) return s;
#ifdef PRED_CORNER
  if (kind == 2) {
    pred_pt[0] = PRED_CORNER(0);
    pred_pt[1] = PRED_CORNER(1);
    pred_pt[2] = PRED_CORNER(2);
    pred_pt[3] = a;
    pred_pt[4] = b;
    return pred_run_exact(44, 61);
  }
#endif
  pred_pt[0] = a;
  pred_pt[1] = b;
  pred_pt[2] = c;
  pred_pt[3] = d;
  return kind == 0 ? pred_run_exact(0, 5) : pred_run_exact(5, 44);
}

int pred_orient2d(dvec2 a, dvec2 b, dvec2 c) { return pred_sign_of(0, a, b, c, c); }

int pred_incircle(dvec2 a, dvec2 b, dvec2 c, dvec2 d) { return pred_sign_of(1, a, b, c, d); }

// CGAL Triangulation_2::side_of_oriented_circle(p0, p1, p2, p, perturb=true); see core/predicates.cpp. Written
// as one loop over the questions it may ask (incircle, then up to three orientations) so that it holds one
// call site of pred_sign_of.
int pred_incircle_perturbed(dvec2 p0, dvec2 p1, dvec2 p2, dvec2 p) {
  // The four points sorted by (x, y), ties in argument order (CGAL's std::sort of four is an insertion sort).
  dvec2 pts[4] = dvec2[4](p0, p1, p2, p);
  int order[4] = int[4](0, 1, 2, 3);
  for (int i = 1; i < 4; ++i) {
    int v = order[i];
    int j = i;
    while (j > 0) {
      dvec2 u = pts[order[j - 1]];
      bool less = pts[v].x < u.x || (pts[v].x == u.x && pts[v].y < u.y);
      if (!less) break;
      order[j] = order[j - 1];
      --j;
    }
    order[j] = v;
  }
  // Step 0: incircle. Steps 1-3: from the largest point down (never the smallest, as in CGAL): the query
  // point decides "outside"; point k of the triangle asks the orientation with p in place of p_k, i.e.
  // k == 2: (p0, p1, p), k == 1: (p0, p, p2), k == 0: (p, p1, p2).
  for (int step = 0; step < 4; ++step) {
    int kind = 1;
    dvec2 a = p0, b = p1, c = p2;
    if (step > 0) {
      int k = order[4 - step];
      if (k == 3) return -1;
      kind = 0;
      if (k == 0) a = p;
      if (k == 1) b = p;
      if (k == 2) c = p;
    }
    int s = pred_sign_of(kind, a, b, c, p);
    if (s != 0) return s;
  }
  return -1;
}

#endif
