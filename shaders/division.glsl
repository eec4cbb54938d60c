// Correctly rounded double division (round to nearest, ties to even), for results that must equal the CPU's
// `a / b` bit for bit. Vulkan guarantees correct rounding for double add, subtract and multiply, but lets
// division be as coarse as single precision's 2.5 ulp; so the device's quotient is refined by two Newton
// steps, then checked, and moved by one ulp at a time, against the two midpoints to its neighbours with
// exact arithmetic:
//   q is the nearest double to a/b  <=>  (q - u_lo/2) * b <= a <= (q + u_hi/2) * b   (b > 0),
// where u_lo, u_hi are the gaps to the neighbouring doubles. (q + h) * b - a = (p - a) + e + h*b with
// q*b = p + e exactly (Dekker, predicates.glsl), p - a exact (Sterbenz: p is within a few ulps of a), and
// h*b exact (h is a power of two); the sign of that three-term sum is taken from its nonoverlapping
// expansion (Shewchuk's grow-expansion), so every decision is exact.
// Valid while a, b, a/b and the products stay normal doubles (|a|, |b| within about 2^-960 .. 2^960):
// outside that range, and for zero, infinite or NaN operands, the device's own quotient is returned.
#ifndef CDTGPU_DIVISION_GLSL
#define CDTGPU_DIVISION_GLSL

#include "predicates.glsl"

// The exact sign of x + y + z.
int div_sign3(double x, double y, double z) {
  double q0, h0, q1, g0, q2, g1;
  pred_two_sum(x, y, q0, h0);  // x + y = q0 + h0, |h0| small
  pred_two_sum(z, h0, q1, g0);
  pred_two_sum(q0, q1, q2, g1);  // x + y + z = q2 + g1 + g0, nonoverlapping, largest last
  if (q2 != 0.0lf) return pred_sign(q2);
  if (g1 != 0.0lf) return pred_sign(g1);
  return pred_sign(g0);
}

bool div_normal(double v) {
  uint hi = unpackDouble2x32(v).y;
  uint e = (hi >> 20) & 0x7FFu;
  return e > 64u && e < 1983u;  // |v| in [2^-958, 2^960): products and their errors stay normal
}

// The neighbouring double of a positive finite q, one step up (dir = 1) or down (dir = -1).
double div_step(double q, int dir) {
  uvec2 w = unpackDouble2x32(q);
  if (dir > 0) {
    w.x += 1u;
    if (w.x == 0u) w.y += 1u;
  } else {
    if (w.x == 0u) w.y -= 1u;
    w.x -= 1u;
  }
  return packDouble2x32(w);
}

// Sign of (q + h) * b - a for q*b = p + e (a, b > 0).
int div_side(double a, double b, double p, double e, double h) {
  precise double pa = p - a;
  precise double hb = h * b;
  return div_sign3(pa, e, hb);
}

// a / b, correctly rounded, starting from the device's quotient q0 (tests pass a perturbed one).
double div_rn_from(double a, double b, double q0) {
  uint sign = (unpackDouble2x32(a).y ^ unpackDouble2x32(b).y) & 0x80000000u;
  precise double A = abs(a);
  precise double B = abs(b);
  precise double q = abs(q0);
  if (A == 0.0lf && B != 0.0lf && div_normal(B)) return packDouble2x32(uvec2(0u, sign));  // IEEE's signed zero
  if (!div_normal(A) || !div_normal(B) || !div_normal(q)) return q0;
  // Vulkan only promises double precision "at least that of single precision" (division: 2.5 single ulps).
  // Two Newton steps on the residual, q += (A - q*B) / B with q*B = p + e exactly (A - p exact while q is
  // within a factor of two), bring such a quotient to within an ulp or two; the loop then decides exactly.
  for (int i = 0; i < 2; ++i) {
    double p, e;
    pred_two_product(q, B, p, e);
    precise double r = (A - p) - e;
    precise double next = q + r / B;
    q = next;
  }
  if (!div_normal(q)) return q0;
  for (int i = 0; i < 8; ++i) {
    double p, e;
    pred_two_product(q, B, p, e);
    precise double up = div_step(q, 1);
    precise double down = div_step(q, -1);
    precise double h_up = (up - q) * 0.5lf;
    precise double h_down = (down - q) * 0.5lf;
    int above = div_side(A, B, p, e, h_up);  // (q + h_up) * B - A
    if (above < 0) {
      q = up;  // a/b lies beyond the upper midpoint
      continue;
    }
    if (above == 0) {  // exactly halfway to `up`: the even one
      if ((unpackDouble2x32(q).x & 1u) != 0u) q = up;
      break;
    }
    int below = div_side(A, B, p, e, h_down);  // (q - h) * B - A
    if (below > 0) {
      q = down;
      continue;
    }
    if (below == 0 && (unpackDouble2x32(q).x & 1u) != 0u) q = down;
    break;
  }
  uvec2 w = unpackDouble2x32(q);
  w.y = (w.y & 0x7FFFFFFFu) | sign;
  return packDouble2x32(w);
}

double div_rn(double a, double b) {
  precise double q = a / b;
  return div_rn_from(a, b, q);
}

#endif
