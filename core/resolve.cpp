// resolve_constraints: splits prepared constraints where they pass through vertices and where they cross, so
// that the result is a planar straight-line graph, with the Steiner points that triangulate_cgal makes.
//
// Rounds. Round 1 tests every constraint; each later round tests only the pieces and Steiner vertices that
// the previous round made (against everything). A round collects events, (piece, vertex strictly inside it)
// and (piece, piece) proper crossings, found in parallel, then sorts them and applies them in that order, so
// the result does not depend on the number of threads or on timing. Applying: every crossing's exact point,
// rounded to the nearest double, becomes a vertex (one per distinct point; an existing vertex there is
// reused); each piece is cut at its events, ordered along it by the exact parameter of the vertex or of the
// unrounded crossing. A rounded point is generally just off both pieces, so the new pieces are tested in the
// next round. Rounds stop when nothing is found (nearly always after round 2; a round-3 cascade needs a
// rounded crossing to land exactly on, or across, another piece).
//
// Finding candidates: a sweep over vertical columns of equal width (about sqrt(n / 4) of them). prepare
// sorts the vertices by x and the constraints by their first (leftmost) end, so a column's vertices are one
// run of the vertex array and the constraints starting in it one run of the constraint array: the sweep
// reads both front to back, keeping the list of constraints that reach the current column. Inside a column,
// vertices and constraints (over the column's x-range) are bucketed by rows, and each row is tested: vertex
// against segment, segment against segment, with orient2d's floating-point filter inlined and the exact
// predicate behind it. Columns and rows are computed with slack for rounding, so a vertex on a segment, or
// the (rounded) crossing of two segments, always falls in a row that both list. Everything a column needs
// stays in cache: on the 2-core development machines a random access beyond ~1 MB costs ~140 ns, and a
// global grid of cells (the first version) paid that on nearly every lookup. The columns are cut into four
// ranges per thread, taken in turn; each range first collects the constraints reaching into it from the left.
// Cost without events: one pass over the vertices, two over the constraints, O(n + m) bucketing, and on the
// benchmark (2M points, 500K constraints) about 2.5 vertex-segment filter tests per vertex and 1.3
// segment-segment tests per constraint. Crossings cost one exact rational intersection each.
#include "core/resolve.hpp"

#include <CGAL/Exact_rational.h>
#include <spdlog/spdlog.h>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <array>
#include <atomic>
#include <bit>
#include <chrono>
#include <cfloat>
#include <cmath>
#include <exception>
#include <execution>
#include <limits>
#include <map>
#include <numeric>
#include <stdexcept>
#include <string>
#include <thread>
#include <utility>

#include "core/compact.hpp"
#include "core/parallel.hpp"
#include "core/predicates.hpp"
#include "core/touched.hpp"

namespace cdtgpu {

namespace {

using pred::XY;
using Q = CGAL::Exact_rational;
constexpr uint32_t kNone = std::numeric_limits<uint32_t>::max();
// A cascade needs each round's rounding to land a new piece on something else; far below this in practice.
constexpr int kMaxRounds = 200;
// From this round on, a crossing of pieces whose rounded point is within kSnapUlps units in the last place (of
// the larger coordinate of the two pieces) of an end of either takes that end (docs/rules.md). Without it, two
// constraints within rounding of one line, crossed by a third, made new crossings beside one point forever:
// where x is near 0 and y near 6e6, each round's vertex moved ~1e-11 along x with y fixed by its ulp (1e-9).
constexpr int kSnapFromRound = 4;
constexpr double kSnapUlps = 4;
// Grid shape: columns of about sqrt(kCellVertices * n) vertices, so that cells of a square domain hold about
// kCellVertices vertices; rows per column: one per kRowItems vertices and segments in the column.
constexpr double kCellVertices = 4;
constexpr size_t kRowItems = 6;

// body(begin, end, worker) over [0, n) in chunks taken from a shared counter by `threads` workers
// (worker < threads). Runs inline for small n. The first exception of a worker is rethrown.
template <class Body>
void parallel_chunks(size_t n, unsigned threads, size_t grain, const Body& body) {
  if (n == 0) return;
  const size_t chunks = std::min<size_t>((n + grain - 1) / grain, size_t(threads) * 8);
  if (threads <= 1 || chunks <= 1) {
    body(size_t(0), n, 0u);
    return;
  }
  std::atomic<size_t> next{0};
  std::vector<std::exception_ptr> errors(threads);
  auto work = [&](unsigned w) {
    try {
      for (size_t c; (c = next.fetch_add(1, std::memory_order_relaxed)) < chunks;)
        body(n * c / chunks, n * (c + 1) / chunks, w);
    } catch (...) {
      errors[w] = std::current_exception();
      next.store(chunks);
    }
  };
  const unsigned used = unsigned(std::min<size_t>(threads, chunks));
  std::vector<std::thread> pool;
  pool.reserve(used - 1);
  for (unsigned w = 1; w < used; ++w) pool.emplace_back(work, w);
  work(0);
  for (std::thread& t : pool) t.join();
  for (const std::exception_ptr& e : errors)
    if (e) std::rethrow_exception(e);
}

// Merging a few sorted items into many sorted ones, as std::merge does (each of the few after the many equal
// to it), with the many moved on all cores: at[j], how many of the many go before few[j], which then lands at
// at[j] + j; spread() hands every one of the many its new place.
template <class T, class Less>
std::vector<size_t> places(const T* many, size_t n, const std::vector<T>& few, Less less) {
  std::vector<size_t> at(few.size());
  for (size_t j = 0; j < few.size(); ++j) at[j] = size_t(std::upper_bound(many, many + n, few[j], less) - many);
  return at;
}

template <class Put>
void spread(size_t n, const std::vector<size_t>& at, unsigned threads, const Put& put) {
  parallel_chunks(n, threads, 1 << 16, [&](size_t b, size_t e, unsigned) {
    size_t j = size_t(std::upper_bound(at.begin(), at.end(), b) - at.begin());
    for (size_t i = b; i < e; ++i) {
      while (j < at.size() && at[j] <= i) ++j;
      put(i, i + j);
    }
  });
}

// ---------------------------------------------------------------------------------------------------------------
// Columns

struct Columns {
  double x0 = 0, sx = 0, w = 0, slack = 0;
  uint32_t n = 1;
  // Monotone: a rounded difference and a rounded product by a positive number never reverse an order, so a
  // point between two others is in a column between theirs.
  uint32_t of(double x) const {
    const double c = (x - x0) * sx;
    return c < 1 ? 0 : c >= double(n) ? n - 1 : uint32_t(c);
  }
  // An interval holding every x with of(x) == c, and every real x whose nearest double is one: of(x) == c
  // implies x >= x0 + c*W/n - ~4 eps W, and computing x0 + c*w errs by ~4 eps (|x0| + W); the slack,
  // 64 eps (|x0| + |x1|), covers both and the half ulp of rounding with room.
  double left(uint32_t c) const { return x0 + c * w - slack; }
  double right(uint32_t c) const { return x0 + (c + 1) * w + slack; }
};

Columns make_columns(double x0, double x1, double count) {
  Columns k;
  k.x0 = x0;
  const double W = x1 - x0;
  if (W > 0 && std::isfinite(W)) {
    k.n = uint32_t(std::clamp(count, 1.0, 65535.0));
    k.sx = k.n / W;
    k.w = W / k.n;
    if (!std::isfinite(k.sx) || !(k.w > 0)) k.n = 1, k.sx = 0, k.w = 0;
  }
  k.slack = 64 * DBL_EPSILON * (std::abs(x0) + std::abs(x1));
  return k;
}

// The y-range of segment ab (a.x <= b.x, columns ca <= cb) over column c: the segment's y at the column's
// x-interval (clamped to the segment), widened by the error of that evaluation (a few eps of |y|).
inline void y_range(const Columns& k, uint32_t c, uint32_t ca, uint32_t cb, XY a, XY b, double& lo,
                    double& hi) {
  lo = std::min(a.y, b.y), hi = std::max(a.y, b.y);
  if (ca == cb || !(b.x > a.x)) return;
  const double xl = c == ca ? a.x : std::max(a.x, k.left(c));
  const double xr = c == cb ? b.x : std::min(b.x, k.right(c));
  const double slope = (b.y - a.y) / (b.x - a.x);
  const double err = 16 * DBL_EPSILON * (std::abs(a.y) + std::abs(b.y));
  const double ya = a.y + (xl - a.x) * slope, yb = a.y + (xr - a.x) * slope;
  const double l = std::max(lo, std::min(ya, yb) - err), h = std::min(hi, std::max(ya, yb) + err);
  if (l <= h) lo = l, hi = h;  // NaN or overflow (far outside the documented range): keep the whole range
}

// ---------------------------------------------------------------------------------------------------------------
// Exact arithmetic, the same as core/cdt_cgal.cpp

// Rounds an exact rational to the nearest double (ties to even). to_double may be off by one ulp, so the
// neighbours are compared exactly.
double round_nearest(const Q& q) {
  const double m = CGAL::to_double(q);
  double best = m;
  Q best_err = CGAL::abs(q - Q(m));
  for (double c : {std::nextafter(m, -HUGE_VAL), std::nextafter(m, HUGE_VAL)}) {
    if (!std::isfinite(c)) continue;
    const Q err = CGAL::abs(q - Q(c));
    if (err < best_err || (err == best_err && (std::bit_cast<uint64_t>(c) & 1) == 0)) {
      best = c;
      best_err = err;
    }
  }
  return best;
}

struct Crossing {
  double x = 0, y = 0;  // the exact crossing rounded to the nearest doubles
  Q u, v;               // its exact parameter along the first and the second segment
  uint32_t vertex = kNone;
};

// Segments ab and cd cross at one point inside both (den != 0).
Crossing intersect(XY a, XY b, XY c, XY d) {
  const Q ax(a.x), ay(a.y), bx(b.x), by(b.y), cx(c.x), cy(c.y), dx(d.x), dy(d.y);
  const Q den = (bx - ax) * (dy - cy) - (by - ay) * (dx - cx);
  Crossing r;
  r.u = ((cx - ax) * (dy - cy) - (cy - ay) * (dx - cx)) / den;
  r.v = ((cx - ax) * (by - ay) - (cy - ay) * (bx - ax)) / den;
  r.x = round_nearest(ax + r.u * (bx - ax));
  r.y = round_nearest(ay + r.u * (by - ay));
  return r;
}

// Exact parameter of w (on line ab) along ab.
Q parameter(XY a, XY b, XY w) {
  const Q ax(a.x), ay(a.y), ux = Q(b.x) - ax, uy = Q(b.y) - ay;
  return ((Q(w.x) - ax) * ux + (Q(w.y) - ay) * uy) / (ux * ux + uy * uy);
}

// ---------------------------------------------------------------------------------------------------------------
// Tests. Nearly every pair a row brings together is far from degenerate; the floating-point filter of
// orient2d (Shewchuk's stage-A bound, as in predicates.cpp), inlined here, settles those with one
// predictable branch, and only near-degenerate ones call the exact predicate.

constexpr double kCcwErrBound = (3.0 + 8.0 * DBL_EPSILON) * (DBL_EPSILON / 2);

inline int orient(XY a, XY b, XY c) {
  const double l = (a.x - c.x) * (b.y - c.y), r = (a.y - c.y) * (b.x - c.x), det = l - r;
  const double bound = kCcwErrBound * (std::abs(l) + std::abs(r));
  if (det > bound) return 1;
  if (-det > bound) return -1;
  return pred::orient2d(a, b, c);
}

// w lies on segment ab, strictly between its ends.
inline bool inside_segment(XY a, XY b, XY w) {
  const double l = (a.x - w.x) * (b.y - w.y), r = (a.y - w.y) * (b.x - w.x), det = l - r;
  if (std::abs(det) > kCcwErrBound * (std::abs(l) + std::abs(r))) return false;
  if (w.x < std::min(a.x, b.x) || w.x > std::max(a.x, b.x) || w.y < std::min(a.y, b.y) ||
      w.y > std::max(a.y, b.y))
    return false;
  if ((w.x == a.x && w.y == a.y) || (w.x == b.x && w.y == b.y)) return false;
  return pred::orient2d(a, b, w) == 0;
}

// Segments ab and cd cross at one point inside both: each has the other's ends strictly on opposite sides.
// Touching is not crossing: an end inside the other segment, or a collinear overlap, is a vertex event.
inline bool cross(XY a, XY b, XY c, XY d) {
  const int o1 = orient(a, b, c), o2 = orient(a, b, d);
  if (o1 * o2 >= 0) return false;
  const int o3 = orient(c, d, a), o4 = orient(c, d, b);
  return o3 * o4 < 0;
}

struct Events {
  std::vector<std::pair<uint32_t, uint32_t>> on;     // (piece, vertex strictly inside it)
  std::vector<std::pair<uint32_t, uint32_t>> cross;  // (p, q), p < q: one crossing point inside both
};

struct Span {
  uint16_t first, last;  // columns of the piece's left and right ends (make_columns makes at most 65535)
};

// What one sweeping thread keeps: the pieces that reach the current column, and the column's rows.
struct SweepState {
  struct Active {
    uint32_t id, first, last, ea, eb;  // piece, its first and last column, its ends (vertex ids)
    XY a, b;                           // a.x <= b.x; later rounds read them only in a dirty column
    bool dirty, have_xy;
    double lo, hi;  // y-range over the current column
  };
  std::vector<Active> active;
  // The column's vertices by row, as arrays (the test loop over a row's vertices is branch-free).
  std::vector<double> vx, vy;
  std::vector<uint32_t> vid, vrow, vstart, sstart, srows;
  std::vector<uint8_t> vdirty, rdirty;  // later rounds: new vertices, rows holding one
  std::vector<std::pair<double, double>> hot;  // later rounds: the column's y-ranges with something new
  std::vector<uint32_t> rhot;                  // later rounds: prefix counts of the rows they reach
  Events events;
};

class Resolver {
 public:
  // Takes the input.
  Resolver(Points&& vertices, std::vector<Edge>&& constraints, unsigned threads)
      : threads_(threads), v_(std::move(vertices)), seg_(std::move(constraints)) {}

  // Copies the input. With several threads the copy runs beside round 1, which reads the caller's arrays
  // meanwhile: 48 MB of vertices take ~30 ms to copy on the 2-core machines, mostly page faults, and that
  // overlaps with the sweep's computing. The copy itself on all cores (TBB): on one, 120 MB (5M vertices)
  // outlasted the sweep on the 16-core H100 machine.
  // `lazily`: the copy only once round 1 has found something to split; a clean input is not copied at all
  // (the result says `unchanged`).
  Resolver(const Points& vertices, const std::vector<Edge>& constraints, unsigned threads,
           ResolveProgress* progress = nullptr, bool lazily = false)
      : threads_(threads), progress_(progress), lazily_(lazily), vr_(&vertices), sr_(&constraints) {
    if (lazily_) return;
    if (threads_ > 1)
      copier_ = std::jthread([this, &vertices, &constraints] { copy_input(vertices, constraints); });
    else
      v_ = vertices, seg_ = constraints;
  }

  ResolvedInput run() {
    ResolvedInput out;
    n0_ = uint32_t(vr_->size());
    m0_ = uint32_t(sr_->size());
    Events ev;
    const auto t0 = std::chrono::steady_clock::now();
    auto ms = [](auto a, auto b) { return std::chrono::duration<double, std::milli>(b - a).count(); };
    if (m0_ > 0) {
      setup();
      const auto t1 = std::chrono::steady_clock::now();
      ev = sweep(/*everything=*/true);
      spdlog::debug("resolve: setup {:.1f} ms, round 1 {:.1f} ms", ms(t0, t1), ms(t1, std::chrono::steady_clock::now()));
    }
    const bool clean = ev.on.empty() && ev.cross.empty();
    if (progress_) progress_->crossings.store(ev.cross.empty() ? 0 : 1);
    const auto t2 = std::chrono::steady_clock::now();
    if (copier_.joinable()) copier_.join();
    if (lazily_) {
      if (clean) {
        out.unchanged = true;
        return out;
      }
      copy_input(*vr_, *sr_);
    }
    spdlog::debug("resolve: waited {:.1f} ms for the input's copy", ms(t2, std::chrono::steady_clock::now()));
    vr_ = &v_, sr_ = &seg_;
    if (clean) {  // the input is already clean: it is the output
      out.vertices = std::move(v_);
      out.constraints = std::move(seg_);
      return out;
    }
    // Room for the pieces to come, so that the rounds' appends do not copy these arrays (and fault their
    // pages) again. On all cores: on one, these took ~2.9 s at 250M constraints.
    reserve_on_all_cores(seg_, with_room(m0_));  // no work where the copy made room
    reserve_on_all_cores(span_, with_room(m0_));
    assign_on_all_cores(origin_, m0_, with_room(m0_), [](size_t p) { return uint32_t(p); });
    assign_on_all_cores(alive_, m0_, with_room(m0_), [](size_t) { return uint8_t(1); });
    assign_on_all_cores(dirty_, m0_, with_room(m0_), [](size_t) { return uint8_t(0); });  // round 1 tested them all
    std::vector<uint32_t> dirty_pieces, dirty_vertices;
    for (int round = 2;; ++round) {
      if (round > kMaxRounds)
        throw std::runtime_error("resolve_constraints: crossings still appear after " +
                                 std::to_string(kMaxRounds) + " rounds of splitting");
      for (uint32_t p : dirty_pieces) dirty_[p] = 0;
      for (uint32_t u : dirty_vertices) vdirty_[u - n0_] = 0;
      dirty_pieces.clear();
      dirty_vertices.clear();
      const auto r0 = std::chrono::steady_clock::now();
      apply(ev, dirty_pieces, dirty_vertices, round >= kSnapFromRound);
      vdirty_.resize(steiner_.size(), 0);
      for (uint32_t u : dirty_vertices) vdirty_[u - n0_] = 1;
      streams(dirty_pieces, dirty_vertices);
      const auto r1 = std::chrono::steady_clock::now();
      ev = sweep(/*everything=*/false);
      spdlog::debug("resolve: round {}: {} new pieces, apply {:.1f} ms, sweep {:.1f} ms", round, dirty_pieces.size(),
                    ms(r0, r1), ms(r1, std::chrono::steady_clock::now()));
      if (ev.on.empty() && ev.cross.empty()) break;
    }
    out.steiner_points = steiner_points_;
    out.split_at_vertices = split_at_vertices_;
    const auto f0 = std::chrono::steady_clock::now();
    finish(out);
    spdlog::debug("resolve: {} Steiner vertices, finish {:.1f} ms", steiner_.size(), ms(f0, std::chrono::steady_clock::now()));
    return out;
  }

 private:
  static size_t with_room(size_t n) { return n + n / 16 + 4096; }

  void copy_input(const Points& vertices, const std::vector<Edge>& constraints) {
    resize_unwritten(v_, vertices.size());
    copy_on_all_cores(vertices.data(), vertices.size(), v_.data());
    const Edge* from = constraints.data();
    assign_on_all_cores(seg_, constraints.size(), with_room(constraints.size()), [from](size_t p) { return from[p]; });
  }
  const Point3& vert(uint32_t i) const { return i < n0_ ? (*vr_)[i] : steiner_[i - n0_]; }
  XY xy(uint32_t i) const { return {vert(i).x, vert(i).y}; }

  Span span_of(uint32_t a, uint32_t b) const {
    const uint32_t ca = cols_.of(vert(a).x), cb = cols_.of(vert(b).x);
    return {uint16_t(std::min(ca, cb)), uint16_t(std::max(ca, cb))};
  }

  // Columns, the vertex run of each, the column span of each constraint and the constraint run starting in
  // each column.
  void setup() {
    // Every vertex and crossing lies in [x0, x1]: the vertices are sorted by x.
    const double x0 = vr_->front().x, x1 = (*vr_)[n0_ - 1].x;
    cols_ = make_columns(x0, x1, std::ceil(std::sqrt(double(n0_) / kCellVertices)));
    const uint32_t nc = cols_.n;
    vfirst_.resize(size_t(nc) + 1);
    vfirst_[nc] = n0_;
    parallel_chunks(nc, threads_, 64, [&](size_t b, size_t e, unsigned) {
      for (size_t c = b; c < e; ++c)
        vfirst_[c] = size_t(std::partition_point(vr_->begin(), vr_->begin() + n0_,
                                                 [&](const Point3& p) { return cols_.of(p.x) < c; }) -
                            vr_->begin());
    });
    compute_spans();
    // prepare's order: a < b, sorted by a, so the first ends' columns ascend, and constraint k starts in
    // column c iff its first end is one of column c's vertices.
    const Edge* S = sr_->data();
    std::vector<uint8_t> ordered(threads_, 1);
    parallel_chunks(m0_, threads_, 16384, [&](size_t b, size_t e, unsigned w) {
      bool ok = true;
      for (size_t k = b; k < e; ++k) ok &= S[k][0] < S[k][1] && (k == 0 || S[k - 1][0] <= S[k][0]);
      if (!ok) ordered[w] = 0;
    });
    if (std::find(ordered.begin(), ordered.end(), 0) == ordered.end()) {
      pfirst_.resize(size_t(nc) + 1);
      pfirst_[nc] = m0_;
      for (size_t c = 0; c < nc; ++c)
        pfirst_[c] =
            size_t(std::partition_point(S, S + m0_, [&](const Edge& f) { return f[0] < vfirst_[c]; }) - S);
      return;
    }
    // Any other order: the constraints sorted by first column.
    prepared_order_.resize(m0_);
    std::iota(prepared_order_.begin(), prepared_order_.end(), 0u);
    std::stable_sort(prepared_order_.begin(), prepared_order_.end(),
                     [&](uint32_t i, uint32_t j) { return span_[i].first < span_[j].first; });
    order_ = prepared_order_;
    starts();
  }

  // The columns of every prepared constraint, reading each far end a little ahead of time (its near end is
  // next to the previous constraint's).
  void compute_spans() {
    span_.reserve(with_room(m0_));
    span_.resize(m0_);
    parallel_chunks(m0_, threads_, 8192, [&](size_t b, size_t e, unsigned) {
      const Point3* V = vr_->data();
      const Edge* S = sr_->data();
      for (size_t k = b; k < e; ++k) {
        if (k + 16 < e) __builtin_prefetch(&V[S[k + 16][1]]);
        span_[k] = span_of(S[k][0], S[k][1]);
      }
    });
  }

  // For each column, the first position in the piece order whose piece starts at or after it.
  void starts() {
    const uint32_t nc = cols_.n;
    pfirst_.resize(size_t(nc) + 1);
    const size_t n = order_.empty() ? m0_ : order_.size();
    parallel_chunks(size_t(nc) + 1, threads_, 64, [&](size_t b, size_t e, unsigned) {
      for (size_t c = b; c < e; ++c) {  // a binary search over the pieces' first columns (ascending)
        size_t lo = 0, hi = n;
        while (lo < hi) {
          const size_t mid = lo + (hi - lo) / 2;
          if (span_[piece_at(mid)].first < c) lo = mid + 1; else hi = mid;
        }
        pfirst_[c] = lo;
      }
    });
  }

  // Rounds 2 and later: the alive pieces in order of their first column, the Steiner vertices by column,
  // and the columns with something new.
  void streams(const std::vector<uint32_t>& new_pieces, const std::vector<uint32_t>& new_vertices) {
    // The prepared constraints keep their order (ascending first columns); the pieces made since are few:
    // sorted on their own and merged in.
    auto by_first = [&](uint32_t i, uint32_t j) {
      return span_[i].first != span_[j].first ? span_[i].first < span_[j].first : i < j;
    };
    auto prepared_at = [&](size_t k) { return prepared_order_.empty() ? uint32_t(k) : prepared_order_[k]; };
    const std::vector<uint32_t> prepared = compact<uint32_t>(
        m0_, [&](size_t k) { return size_t(alive_[prepared_at(k)]); },
        [&](size_t k, uint32_t* to) {
          if (alive_[prepared_at(k)]) *to++ = prepared_at(k);
          return to;
        });
    std::vector<uint32_t> made;
    for (uint32_t p = m0_; p < sr_->size(); ++p)
      if (alive_[p]) made.push_back(p);
    std::sort(made.begin(), made.end(), by_first);
    const std::vector<size_t> at = places(prepared.data(), prepared.size(), made, [&](uint32_t i, uint32_t j) {
      return span_[i].first < span_[j].first;
    });
    order_.resize(prepared.size() + made.size());
    spread(prepared.size(), at, threads_, [&](size_t i, size_t to) { order_[to] = prepared[i]; });
    for (size_t j = 0; j < made.size(); ++j) order_[at[j] + j] = made[j];
    starts();
    const uint32_t nc = cols_.n;
    std::vector<uint32_t> steiner(steiner_.size());
    std::iota(steiner.begin(), steiner.end(), n0_);
    std::vector<uint32_t> scol(steiner.size());
    for (size_t i = 0; i < steiner.size(); ++i) scol[i] = cols_.of(vert(steiner[i]).x);
    sfirst_.assign(size_t(nc) + 1, 0);
    for (uint32_t c : scol) ++sfirst_[c + 1];
    std::partial_sum(sfirst_.begin(), sfirst_.end(), sfirst_.begin());
    sorder_.resize(steiner.size());
    std::vector<uint32_t> cursor(sfirst_.begin(), sfirst_.end() - 1);
    for (size_t i = 0; i < steiner.size(); ++i) sorder_[cursor[scol[i]]++] = steiner[i];
    col_dirty_.assign(nc, 0);
    for (uint32_t p : new_pieces)
      for (uint32_t c = span_[p].first; c <= span_[p].last; ++c) col_dirty_[c] = 1;
    for (uint32_t u : new_vertices) col_dirty_[cols_.of(vert(u).x)] = 1;
  }

  // One round's events. Round 1 (everything): every pair is new. Later rounds: only pairs with a dirty
  // piece or vertex, in the columns marked dirty.
  Events sweep(bool everything) {
    const uint32_t nc = cols_.n;
    // Ranges of columns of about equal work (vertices and pieces that start there).
    std::vector<double> work(size_t(nc) + 1, 0);
    for (uint32_t c = 0; c < nc; ++c) {
      const bool busy = everything || col_dirty_[c];
      work[c + 1] = work[c] + 1 +
                    (busy ? double(vfirst_[c + 1] - vfirst_[c]) + double(pfirst_[c + 1] - pfirst_[c]) : 0);
    }
    // A few ranges per thread, taken in turn: the threads finish together. Each range starts by finding the
    // pieces that reach into it from the left (a scan of the piece order before it).
    const unsigned ranges = threads_ > 1 && work[nc] > 65536 ? threads_ * 4 : 1;
    std::vector<uint32_t> bound(ranges + 1, nc);
    for (unsigned t = 0; t < ranges; ++t)
      bound[t] =
          uint32_t(std::lower_bound(work.begin(), work.end() - 1, work[nc] * t / ranges) - work.begin());
    // reach_[b]: the largest last column of the pieces in blocks 0..b of the piece order.
    const size_t pieces = order_.empty() ? m0_ : order_.size();
    reach_.assign((pieces + kReachBlock - 1) / kReachBlock, 0);
    parallel_chunks(reach_.size(), threads_, 64, [&](size_t b0, size_t b1, unsigned) {
      for (size_t b = b0; b < b1; ++b)
        for (size_t k = b * kReachBlock; k < std::min(pieces, (b + 1) * kReachBlock); ++k)
          reach_[b] = std::max<uint32_t>(reach_[b], span_[piece_at(k)].last);
    });
    for (size_t b = 1; b < reach_.size(); ++b) reach_[b] = std::max(reach_[b], reach_[b - 1]);
    std::vector<SweepState> states(ranges);
    parallel_chunks(ranges, threads_, 1, [&](size_t t0, size_t t1, unsigned) {
      for (size_t t = t0; t < t1; ++t) {
        if (everything)
          sweep_range<true>(bound[t], bound[t + 1], states[t]);
        else
          sweep_range<false>(bound[t], bound[t + 1], states[t]);
      }
    });
    Events all;
    for (SweepState& st : states) {
      all.on.insert(all.on.end(), st.events.on.begin(), st.events.on.end());
      all.cross.insert(all.cross.end(), st.events.cross.begin(), st.events.cross.end());
    }
    for (auto* list : {&all.on, &all.cross}) {
      std::sort(list->begin(), list->end());
      list->erase(std::unique(list->begin(), list->end()), list->end());
    }
    return all;
  }

  uint32_t piece_at(size_t k) const { return order_.empty() ? uint32_t(k) : order_[k]; }

  template <bool kAll>
  void sweep_range(uint32_t c0, uint32_t c1, SweepState& s) const {
    auto add = [&](uint32_t id) {
      const Edge& e = (*sr_)[id];
      s.active.push_back(
          {id, span_[id].first, span_[id].last, e[0], e[1], {}, {}, kAll || dirty_[id] != 0, false, 0, 0});
      if (kAll) gather(s.active.back());
    };
    // Pieces that start left of the range and reach into it: those after the first block whose running
    // maximum of last columns reaches c0 (scanning from the start, each of 64 ranges read 2 GB at 1B points).
    const size_t from =
        size_t(std::partition_point(reach_.begin(), reach_.end(), [&](uint32_t r) { return r < c0; }) -
               reach_.begin()) * kReachBlock;
    for (size_t k = from; k < pfirst_[c0]; ++k)
      if (span_[piece_at(k)].last >= c0) add(piece_at(k));
    const Point3* V = vr_->data();
    for (uint32_t c = c0; c < c1; ++c) {
      if (kAll && c + 2 < cols_.n)  // the vertex run two columns ahead: far ends of pieces land there
        for (size_t i = vfirst_[c + 2]; i < vfirst_[c + 3]; i += 64 / sizeof(Point3))
          __builtin_prefetch(V + i);
      for (size_t k = pfirst_[c]; k < pfirst_[c + 1]; ++k) add(piece_at(k));
      // Pieces that ended are dropped every few columns (column() skips them meanwhile): compacting the
      // list every column would copy it every column.
      if (c % 8 == 0) std::erase_if(s.active, [&](const SweepState::Active& a) { return a.last < c; });
      if (s.active.empty() || !(kAll || col_dirty_[c])) continue;
      column<kAll>(c, s);
    }
  }

  void gather(SweepState::Active& a) const {
    a.a = xy(a.ea), a.b = xy(a.eb);
    if (a.b.x < a.a.x) std::swap(a.a, a.b);
    a.have_xy = true;
  }

  template <bool kAll>
  void column(uint32_t c, SweepState& s) const {
    double ylo = HUGE_VAL, yhi = -HUGE_VAL;
    for (SweepState::Active& a : s.active) {
      if (a.last < c) continue;
      if (!kAll && !a.have_xy) gather(a);
      y_range(cols_, c, a.first, a.last, a.a, a.b, a.lo, a.hi);
      ylo = std::min(ylo, a.lo), yhi = std::max(yhi, a.hi);
    }
    // Candidate vertices: the column's prepared ones and (later rounds) its Steiner ones.
    const size_t vb = vfirst_[c], nv = vfirst_[c + 1] - vb;
    const size_t ns = kAll ? 0 : sfirst_[c + 1] - sfirst_[c];
    auto vertex = [&](size_t k) { return k < nv ? uint32_t(vb + k) : sorder_[sfirst_[c] + (k - nv)]; };
    // Later rounds: every new event has a new piece or vertex in it, so only the y-ranges of those (`hot`)
    // matter; the column's other vertices and pieces are left out (a ring crossing the contours dirties
    // every column, but only where it passes).
    if (!kAll && !hot_ranges(c, s, ylo, yhi)) return;
    // Rows: monotone in y like the columns in x, so a point between two y's is in a row between theirs.
    const size_t rows = std::min<size_t>((nv + ns + s.active.size()) / kRowItems + 1, 1u << 16);
    double sy = yhi > ylo ? double(rows) / (yhi - ylo) : 0;
    if (!std::isfinite(sy)) sy = 0;
    auto row = [&](double y) {
      const double r = (y - ylo) * sy;
      return r < 1 ? uint32_t(0) : r >= double(rows) ? uint32_t(rows - 1) : uint32_t(r);
    };
    // Later rounds: the rows that a hot range reaches (s.rhot: how many of rows 0 .. r - 1 are).
    if (!kAll) {
      s.rhot.assign(rows + 1, 0);
      for (const auto& [lo, hi] : s.hot)
        for (uint32_t r = row(lo), r1 = row(hi); r <= r1; ++r) s.rhot[r + 1] = 1;
      std::partial_sum(s.rhot.begin(), s.rhot.end(), s.rhot.begin());
    }
    auto hot_row = [&](uint32_t r) { return kAll || s.rhot[r + 1] != s.rhot[r]; };
    auto listed = [&](const SweepState::Active& a) {
      return a.last >= c && (kAll || (a.hi >= ylo && a.lo <= yhi && s.rhot[row(a.hi) + 1] != s.rhot[row(a.lo)]));
    };
    const Point3* V = vr_->data();
    s.vstart.assign(rows + 1, 0);
    s.vrow.resize(nv + ns);
    auto place = [&](size_t k, double y) {  // no branches: whether a vertex is in is anyone's guess
      const uint32_t r = row(y);
      const bool in = (y >= ylo) & (y <= yhi) & hot_row(r);  // no piece reaches the others
      s.vrow[k] = in ? r : kNone;
      s.vstart[r + 1] += in;
    };
    for (size_t k = 0; k < nv; ++k) place(k, V[vb + k].y);
    for (size_t k = nv; k < nv + ns; ++k) place(k, vert(vertex(k)).y);
    std::partial_sum(s.vstart.begin(), s.vstart.end(), s.vstart.begin());
    const size_t nin = s.vstart[rows];
    s.vx.resize(nin), s.vy.resize(nin), s.vid.resize(nin);
    if (!kAll) s.vdirty.resize(nin);
    for (size_t k = 0; k < nv + ns; ++k) {
      if (s.vrow[k] == kNone) continue;
      const uint32_t at = s.vstart[s.vrow[k]]++, u = vertex(k);
      const Point3& w = kAll ? V[u] : vert(u);
      s.vx[at] = w.x, s.vy[at] = w.y, s.vid[at] = u;
      if (!kAll) s.vdirty[at] = u < n0_ ? 0 : vdirty_[u - n0_];
    }
    for (size_t r = rows; r > 0; --r) s.vstart[r] = s.vstart[r - 1];
    s.vstart[0] = 0;
    // Later rounds: a clean piece can meet only the new vertices of its rows.
    if (!kAll) {
      s.rdirty.assign(rows, 0);
      for (size_t r = 0; r < rows; ++r)
        for (uint32_t j = s.vstart[r]; j < s.vstart[r + 1]; ++j) s.rdirty[r] |= s.vdirty[j];
    }
    s.sstart.assign(rows + 1, 0);
    for (const auto& a : s.active)
      if (listed(a))
        for (uint32_t r = row(a.lo), r1 = row(a.hi); r <= r1; ++r) s.sstart[r + 1] += hot_row(r);
    std::partial_sum(s.sstart.begin(), s.sstart.end(), s.sstart.begin());
    s.srows.resize(s.sstart[rows]);
    for (uint32_t i = 0; i < s.active.size(); ++i)
      if (listed(s.active[i]))
        for (uint32_t r = row(s.active[i].lo), r1 = row(s.active[i].hi); r <= r1; ++r)
          if (hot_row(r)) s.srows[s.sstart[r]++] = i;
    for (size_t r = rows; r > 0; --r) s.sstart[r] = s.sstart[r - 1];
    s.sstart[0] = 0;

    const double* X = s.vx.data();
    const double* Y = s.vy.data();
    for (size_t r = 0; r < rows; ++r) {
      const uint32_t v0 = s.vstart[r], v1 = s.vstart[r + 1], s0 = s.sstart[r], s1 = s.sstart[r + 1];
      for (uint32_t i = s0; i < s1; ++i) {
        const SweepState::Active& p = s.active[s.srows[i]];
        // Vertex on piece: the filter over the whole row first (no branches), exact work only if it flags
        // a vertex other than the piece's ends.
        const XY a = p.a, b = p.b;
        bool maybe = false;
        if (kAll || p.dirty || s.rdirty[r])
          for (uint32_t j = v0; j < v1; ++j) {
            const double l = (a.x - X[j]) * (b.y - Y[j]), rr = (a.y - Y[j]) * (b.x - X[j]);
            const bool end = (X[j] == a.x && Y[j] == a.y) | (X[j] == b.x && Y[j] == b.y);
            maybe |= (std::abs(l - rr) <= kCcwErrBound * (std::abs(l) + std::abs(rr))) & !end;
          }
        if (maybe)
          for (uint32_t j = v0; j < v1; ++j)
            if ((kAll || p.dirty || s.vdirty[j]) && s.vid[j] != p.ea && s.vid[j] != p.eb &&
                inside_segment(a, b, XY{X[j], Y[j]}))
              s.events.on.push_back({p.id, s.vid[j]});
        for (uint32_t j = i + 1; j < s1; ++j) {
          const SweepState::Active& q = s.active[s.srows[j]];
          if (!(kAll || p.dirty || q.dirty) || p.ea == q.ea || p.ea == q.eb || p.eb == q.ea || p.eb == q.eb)
            continue;
          if (cross(a, b, q.a, q.b)) s.events.cross.push_back({std::min(p.id, q.id), std::max(p.id, q.id)});
        }
      }
    }
  }

  // The y-ranges of column c's new pieces and its new vertices into s.hot, and their hull into
  // ylo, yhi; false when there are none.
  bool hot_ranges(uint32_t c, SweepState& s, double& ylo, double& yhi) const {
    s.hot.clear();
    for (const auto& a : s.active)
      if (a.last >= c && a.dirty) s.hot.push_back({a.lo, a.hi});
    for (size_t k = sfirst_[c]; k < sfirst_[c + 1]; ++k)
      if (vdirty_[sorder_[k] - n0_]) s.hot.push_back({vert(sorder_[k]).y, vert(sorder_[k]).y});
    if (s.hot.empty()) return false;
    ylo = HUGE_VAL, yhi = -HUGE_VAL;
    for (const auto& [lo, hi] : s.hot) ylo = std::min(ylo, lo), yhi = std::max(yhi, hi);
    return true;
  }

  // The end of `ends` nearest the crossing (Chebyshev distance, ties to the smaller index), if it is within
  // kSnapUlps units in the last place of the largest coordinate of the ends: the crossing's point becomes it.
  void snap_to_end(Crossing& c, const std::array<uint32_t, 4>& ends) const {
    double mag = 0;
    for (uint32_t w : ends) mag = std::max({mag, std::abs(vert(w).x), std::abs(vert(w).y)});
    const double reach = kSnapUlps * mag * DBL_EPSILON;
    uint32_t best = kNone;
    double best_d = HUGE_VAL;
    for (uint32_t w : ends) {
      const double d = std::max(std::abs(vert(w).x - c.x), std::abs(vert(w).y - c.y));
      if (d <= reach && (d < best_d || (d == best_d && w < best))) best = w, best_d = d;
    }
    if (best == kNone) return;
    c.x = vert(best).x;
    c.y = vert(best).y;
  }

  uint32_t existing_vertex(double x, double y) const {
    // Only the point's column can hold it (a short search, in cache when the points come in x order).
    const uint32_t c = cols_.of(x);
    const auto lo = v_.begin() + ptrdiff_t(vfirst_[c]), hi = v_.begin() + ptrdiff_t(vfirst_[c + 1]);
    auto it = std::lower_bound(lo, hi, std::pair<double, double>(x, y),
                               [](const Point3& p, const std::pair<double, double>& q) {
                                 return p.x != q.first ? p.x < q.first : p.y < q.second;
                               });
    if (it != hi && it->x == x && it->y == y) return uint32_t(it - v_.begin());
    auto s = steiner_at_.find({x, y});
    return s == steiner_at_.end() ? kNone : s->second;
  }

  // snap: a crossing whose rounded point is within kSnapUlps of an end of either piece takes that end.
  void apply(const Events& ev, std::vector<uint32_t>& new_pieces, std::vector<uint32_t>& new_vertices,
             bool snap = false) {
    // Crossings, exactly (in parallel: each is independent).
    std::vector<Crossing> cr(ev.cross.size());
    parallel_chunks(cr.size(), threads_, 64, [&](size_t b, size_t e, unsigned) {
      for (size_t i = b; i < e; ++i) {
        const Edge &s = seg_[ev.cross[i].first], &t = seg_[ev.cross[i].second];
        cr[i] = intersect(xy(s[0]), xy(s[1]), xy(t[0]), xy(t[1]));
        if (snap) snap_to_end(cr[i], {s[0], s[1], t[0], t[1]});
      }
    });
    // One vertex per distinct rounded point, numbered in (x, y) order; an existing vertex there is reused.
    std::vector<uint32_t> order(cr.size());
    std::iota(order.begin(), order.end(), 0u);
    std::sort(order.begin(), order.end(), [&](uint32_t i, uint32_t j) {
      return cr[i].x != cr[j].x ? cr[i].x < cr[j].x : cr[i].y != cr[j].y ? cr[i].y < cr[j].y : i < j;
    });
    for (size_t k = 0; k < order.size(); ++k) {
      Crossing& c = cr[order[k]];
      if (k > 0 && cr[order[k - 1]].x == c.x && cr[order[k - 1]].y == c.y) {
        c.vertex = cr[order[k - 1]].vertex;
        continue;
      }
      c.vertex = existing_vertex(c.x, c.y);
      if (c.vertex != kNone) continue;
      if (n0_ + steiner_.size() >= kNone - 1)
        throw std::length_error("resolve_constraints: too many vertices");
      c.vertex = uint32_t(n0_ + steiner_.size());
      steiner_.push_back({c.x, c.y, 0.0});
      steiner_at_.emplace(std::pair<double, double>(c.x, c.y), c.vertex);
      new_vertices.push_back(c.vertex);
      ++steiner_points_;
    }

    // The cuts of each piece: (piece, vertex, crossing index or kNone for a vertex on the piece).
    // A crossing that rounds to a vertex exactly on the piece is a vertex event too: vertex cuts sort first
    // among equal ones, so the split counts as one at a vertex.
    struct Cut {
      uint32_t piece, vertex, cross;
      bool operator<(const Cut& o) const {
        return piece != o.piece     ? piece < o.piece
               : vertex != o.vertex ? vertex < o.vertex
                                    : cross + 1 < o.cross + 1;
      }
    };
    std::vector<Cut> cuts;
    cuts.reserve(ev.on.size() + 2 * ev.cross.size());
    for (const auto& [p, w] : ev.on) cuts.push_back({p, w, kNone});
    for (uint32_t i = 0; i < ev.cross.size(); ++i) {
      cuts.push_back({ev.cross[i].first, cr[i].vertex, i});
      cuts.push_back({ev.cross[i].second, cr[i].vertex, i});
    }
    std::sort(cuts.begin(), cuts.end());

    // At most one new piece per cut and per cut piece: room for them up front (these arrays are large).
    const size_t room = seg_.size() + 2 * cuts.size();
    reserve_on_all_cores(seg_, room), reserve_on_all_cores(span_, room), reserve_on_all_cores(origin_, room),
        reserve_on_all_cores(alive_, room), reserve_on_all_cores(dirty_, room);
    std::vector<std::pair<double, uint32_t>> by_coord;  // (coordinate along the piece, cut)
    std::vector<std::pair<Q, uint32_t>> by_param;       // (exact parameter, cut)
    std::vector<uint32_t> chain, sorted;
    for (size_t g = 0; g < cuts.size();) {
      const uint32_t p = cuts[g].piece;
      const Edge e = seg_[p];
      // This piece's cuts, one per vertex (the first: a vertex cut if there is one), ends excluded.
      size_t end = g;
      bool crossing = false;
      sorted.clear();
      for (; end < cuts.size() && cuts[end].piece == p; ++end) {
        const uint32_t w = cuts[end].vertex;
        if (w == e[0] || w == e[1] || (end > g && cuts[end - 1].vertex == w)) continue;
        sorted.push_back(uint32_t(end));
        crossing |= cuts[end].cross != kNone;
      }
      const XY a = xy(e[0]), b = xy(e[1]);
      if (!crossing) {
        // Every cut is exactly on the piece: one coordinate orders them exactly.
        by_coord.clear();
        for (uint32_t k : sorted) {
          const XY w = xy(cuts[k].vertex);
          by_coord.push_back({a.x != b.x ? (b.x > a.x ? w.x : -w.x) : (b.y > a.y ? w.y : -w.y), k});
        }
        std::sort(by_coord.begin(), by_coord.end());
        for (size_t i = 0; i < by_coord.size(); ++i) sorted[i] = by_coord[i].second;
      } else {
        // Rounded crossings are off the piece: order by the exact parameter of the unrounded crossing.
        by_param.clear();
        for (uint32_t k : sorted) {
          const Cut& c = cuts[k];
          Q t = c.cross == kNone               ? parameter(a, b, xy(c.vertex))
                : ev.cross[c.cross].first == p ? cr[c.cross].u
                                               : cr[c.cross].v;
          by_param.push_back({std::move(t), k});
        }
        std::sort(by_param.begin(), by_param.end());
        for (size_t i = 0; i < by_param.size(); ++i) sorted[i] = by_param[i].second;
      }
      chain.assign(1, e[0]);
      uint64_t at_vertices = 0;
      for (uint32_t k : sorted) {
        chain.push_back(cuts[k].vertex);
        at_vertices += cuts[k].cross == kNone;
      }
      chain.push_back(e[1]);
      g = end;
      if (chain.size() == 2) continue;
      split_at_vertices_ += at_vertices;
      alive_[p] = 0;
      for (size_t k = 0; k + 1 < chain.size(); ++k) {
        if (seg_.size() >= kNone - 1) throw std::length_error("resolve_constraints: too many pieces");
        new_pieces.push_back(uint32_t(seg_.size()));
        seg_.push_back({chain[k], chain[k + 1]});
        span_.push_back(span_of(chain[k], chain[k + 1]));
        origin_.push_back(origin_[p]);
        alive_.push_back(1);
        dirty_.push_back(1);
      }
    }
  }

  void finish(ResolvedInput& out) {
    // z of a Steiner vertex: along the lowest-indexed prepared constraint whose pieces end at it, with the
    // arithmetic of triangulate_cgal.
    const uint32_t ns = uint32_t(steiner_.size());
    std::vector<uint32_t> along(ns, kNone);
    for (uint32_t p = m0_; p < seg_.size(); ++p)  // the prepared constraints end at prepared vertices
      if (alive_[p])
        for (uint32_t w : seg_[p])
          if (w >= n0_) along[w - n0_] = std::min(along[w - n0_], origin_[p]);
    for (uint32_t s = 0; s < ns; ++s) {
      Point3& v = steiner_[s];
      if (along[s] == kNone) continue;
      const Point3& a = v_[seg_[along[s]][0]];  // pieces below m0_ are the prepared constraints
      const Point3& b = v_[seg_[along[s]][1]];
      const double len = std::hypot(b.x - a.x, b.y - a.y);
      const double t = len > 0 ? std::min(1.0, std::hypot(v.x - a.x, v.y - a.y) / len) : 0.0;
      v.z = a.z + t * (b.z - a.z);
    }
    // Canonical vertex order: the Steiner vertices, sorted, merged into the prepared ones (none equal), on all
    // cores (2M vertices took ~20 ms on one).
    std::vector<uint32_t> order(ns);
    std::iota(order.begin(), order.end(), 0u);
    auto less = [](const Point3& p, const Point3& q) { return p.x != q.x ? p.x < q.x : p.y < q.y; };
    std::sort(order.begin(), order.end(),
              [&](uint32_t i, uint32_t j) { return less(steiner_[i], steiner_[j]); });
    std::vector<Point3> sorted(ns);
    for (uint32_t k = 0; k < ns; ++k) sorted[k] = steiner_[order[k]];
    // No Steiner vertex (only splits at vertices): the prepared vertices are the output, numbers and all,
    // and are not copied (a copy beside them was 24 bytes a vertex of the resolve's peak).
    RawVector<uint32_t> renum;
    if (ns == 0) {
      out.vertices = std::move(v_);
    } else {
      const std::vector<size_t> at = places(v_.data(), n0_, sorted, less);
      resize_unwritten(renum, size_t(n0_) + ns);
      resize_unwritten(out.vertices, renum.size());
      Point3* V = out.vertices.data();
      spread(n0_, at, threads_, [&](size_t i, size_t to) {
        renum[i] = uint32_t(to);
        V[to] = v_[i];
      });
      for (uint32_t k = 0; k < ns; ++k) {
        renum[n0_ + order[k]] = uint32_t(at[k] + k);
        V[at[k] + k] = sorted[k];
      }
    }

    // Constraints: the prepared ones left whole keep their sorted order (renumbering keeps the (x, y)
    // order), renumbered on all cores; the pieces are sorted and merged in.
    auto renumbered = [&](uint32_t p) {
      uint32_t a = seg_[p][0], b = seg_[p][1];
      if (ns > 0) a = renum[a], b = renum[b];
      return a < b ? Edge{a, b} : Edge{b, a};
    };
    std::vector<Edge> kept = compact<Edge>(
        m0_, [&](size_t p) { return size_t(alive_[p]); },
        [&](size_t p, Edge* to) {
          if (alive_[p]) *to++ = renumbered(uint32_t(p));
          return to;
        });
    std::vector<Edge> pieces;
    for (uint32_t p = m0_; p < seg_.size(); ++p)
      if (alive_[p]) pieces.push_back(renumbered(p));
    std::sort(pieces.begin(), pieces.end());
    if (!std::is_sorted(std::execution::par, kept.begin(), kept.end()))
      std::sort(std::execution::par, kept.begin(), kept.end());
    std::vector<Edge>& cs = out.constraints;
    if (pieces.empty()) {
      cs = std::move(kept);
    } else {
      const std::vector<size_t> where = places(kept.data(), kept.size(), pieces, std::less<Edge>());
      resize_touched(cs, kept.size() + pieces.size());
      spread(kept.size(), where, threads_, [&](size_t i, size_t to) { cs[to] = kept[i]; });
      for (size_t j = 0; j < pieces.size(); ++j) cs[where[j] + j] = pieces[j];
    }
    // Equal pieces (collinear overlaps) merge; one core's unique over 250M took ~0.5 s where none are.
    if (std::adjacent_find(std::execution::par, cs.begin(), cs.end()) != cs.end())
      cs.erase(std::unique(cs.begin(), cs.end()), cs.end());
  }

  const unsigned threads_;
  ResolveProgress* const progress_ = nullptr;
  const bool lazily_ = false;
  Points v_;        // prepared vertices
  Points steiner_;  // Steiner vertices in creation order: vertex n0_ + i is steiner_[i]
  std::vector<Edge> seg_;        // prepared constraints, then the pieces of splits (in order along them)
  // What rounds read: the caller's arrays while they are being copied, then v_ and seg_.
  const Points* vr_ = &v_;
  const std::vector<Edge>* sr_ = &seg_;
  std::jthread copier_;           // declared after v_ and seg_: destroyed (joined) before them
  std::vector<Span> span_;        // columns of each piece
  std::vector<uint32_t> origin_;  // the prepared constraint each piece lies along
  std::vector<uint8_t> alive_, dirty_, vdirty_, col_dirty_;
  uint32_t n0_ = 0, m0_ = 0;
  Columns cols_;
  std::vector<size_t> vfirst_;            // prepared vertices of column c: [vfirst_[c], vfirst_[c + 1])
  std::vector<uint32_t> prepared_order_;  // prepared constraints by first column (empty: 0, 1, 2, ... are)
  std::vector<uint32_t> order_;   // the pieces of this round by first column (empty: 0, 1, 2, ... are)
  std::vector<size_t> pfirst_;    // pieces starting in column c: order_[pfirst_[c] .. pfirst_[c + 1])
  static constexpr size_t kReachBlock = 4096;
  std::vector<uint32_t> reach_;   // per block of kReachBlock pieces in order_: the running maximum of last columns
  std::vector<uint32_t> sorder_;  // Steiner vertices by column
  std::vector<size_t> sfirst_;    // Steiner vertices of column c: sorder_[sfirst_[c] .. sfirst_[c + 1])
  std::map<std::pair<double, double>, uint32_t> steiner_at_;
  uint64_t steiner_points_ = 0, split_at_vertices_ = 0;
};

}  // namespace

namespace {
unsigned thread_count(unsigned threads) {
  if (threads == 0) threads = std::max(1u, std::thread::hardware_concurrency());
  return std::min(threads, 256u);
}
}  // namespace

ResolvedInput resolve_constraints(const PreparedInput& prepared, unsigned threads) {
  return Resolver(prepared.vertices, prepared.constraints, thread_count(threads)).run();
}

ResolvedInput resolve_constraints(const PreparedInput& prepared, ResolveProgress& progress, unsigned threads) {
  return Resolver(prepared.vertices, prepared.constraints, thread_count(threads), &progress).run();
}

ResolvedInput resolve_if_needed(const PreparedInput& prepared, unsigned threads) {
  return Resolver(prepared.vertices, prepared.constraints, thread_count(threads), nullptr, /*lazily=*/true).run();
}

ResolvedInput resolve_constraints(PreparedInput&& prepared, unsigned threads) {
  return Resolver(std::move(prepared.vertices), std::move(prepared.constraints), thread_count(threads)).run();
}

}  // namespace cdtgpu
