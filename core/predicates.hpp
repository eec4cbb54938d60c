// Exact-sign geometric predicates on doubles: orient2d, incircle and CGAL's symbolically perturbed incircle.
// A Shewchuk-style floating-point filter decides almost every call; the rest fall to an exact stage in
// expansion arithmetic (TwoSum, Dekker products, no fma) that shaders/predicates.glsl mirrors step for step,
// so the CPU and the GPU return the same signs.
//
// Range of exactness: every coordinate is 0 or has 2^-190 <= |x| <= 2^250 (about 6.4e-58 .. 1.8e75).
// Then every coordinate is a multiple of 2^-242, so every intermediate of degree <= 4 (the highest the
// predicates reach) is a multiple of 2^-968: nothing is lost to underflow, and even the filter's error
// bound (about 2^-50 times a degree-4 sum) stays a normal number. Degree-4 magnitudes stay below 2^1016, so
// nothing overflows. GIS data (|x| < 1e9, UTM northings of 6e6 with millimetre or finer detail) is far
// inside. Extents like 1e-300 are out of range: products underflow and signs may be wrong there (CGAL
// would still be exact).
#pragma once

namespace cdtgpu::pred {

struct XY {
  double x = 0, y = 0;
};

// +1 if a, b, c turn counter-clockwise (CGAL LEFT_TURN), -1 clockwise, 0 collinear.
int orient2d(XY a, XY b, XY c);

// +1 if d lies inside the circle through a, b, c when a, b, c are counter-clockwise (CGAL
// side_of_oriented_circle == ON_POSITIVE_SIDE), -1 outside, 0 co-circular. The sign flips with the
// orientation of a, b, c, as in CGAL.
int incircle(XY a, XY b, XY c, XY d);

// CGAL Triangulation_2::side_of_oriented_circle(p0, p1, p2, p, perturb=true): incircle, and when that is
// 0 a symbolic perturbation decided by the lexicographic (x, y) order of the four points. Like CGAL it
// assumes nothing about p0, p1, p2: the perturbation is consistent (a valid Delaunay tie-break) when they
// are counter-clockwise, and for other inputs it returns what CGAL's code returns.
int incircle_perturbed(XY p0, XY p1, XY p2, XY p);

// The exact stages alone (no filter), for tests.
int orient2d_exact(XY a, XY b, XY c);
int incircle_exact(XY a, XY b, XY c, XY d);

}  // namespace cdtgpu::pred
