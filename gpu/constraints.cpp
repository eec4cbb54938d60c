// Constraint insertion on the GPU; see constraints.hpp and docs/gpu-constraints.md. insert() reads as the method:
//   vertex map -> rounds of { crossing detection (walk, scan, walk), adaptive flipping (claim, flip, fix) }
//   -> mark the constrained edges -> rounds of { legalise (claim, flip, fix) }.
// Rounds are recorded in batches into one command buffer; between batches only counters are read back.
#include "gpu/constraints.hpp"

#include <tbb/blocked_range.h>
#include <tbb/parallel_reduce.h>
#include <tbb/parallel_sort.h>

#include <algorithm>
#include <cmath>
#include <chrono>
#include <execution>
#include <optional>
#include <stdexcept>
#include <unordered_map>

#include <spdlog/spdlog.h>

#include "core/parallel.hpp"
#include "core/predicates.hpp"
#include "core/timing.hpp"
#include "core/touched.hpp"
#include "core/tiles.hpp"

#include "gpu/check.hpp"
#include "gpu/profiler.hpp"
#include "gpu/recorder.hpp"
#include "shaders/layout_cdt.h"

namespace cdtgpu::gpu {

using namespace layout;

namespace {

constexpr const char* kFlagsKey = "cdt constrained bits";  // the result's flags, in the cache (recycle)
constexpr const char* kConstraintsKey = "cdt constraints";     // the list, when not uploaded by the caller
constexpr const char* kSplitKey = "cdt constraints split";     // a split list made from that one
constexpr uint32_t kMaxBatch = 64;  // rounds per command buffer once the first batches did not finish

uint64_t groups(uint64_t items) { return (items + CDT_WG - 1) / CDT_WG; }

// Stage times summed over the batches, in first-seen order.
struct StageClock {
  std::vector<std::pair<std::string, double>> stages;
  void add(const Profiler& prof) {
    for (const StageTime& s : prof.results()) {
      auto it = std::find_if(stages.begin(), stages.end(), [&](const auto& e) { return e.first == s.name; });
      if (it == stages.end())
        stages.emplace_back(s.name, s.ms);
      else
        it->second += s.ms;
    }
  }
};

// Rounds to record next: enough for the crossings to fall to zero at the rate of the last two rounds (they shrink
// geometrically), plus two, so few rounds run idle after the end and few batches are needed.
uint32_t predict_rounds(uint32_t before, uint32_t last) {
  if (last == 0) return 1;
  const double rate = std::clamp(before ? double(last) / before : 0.5, 0.2, 0.9);
  const double rounds = std::log(double(last) + 1) / -std::log(rate) + 2;
  return std::clamp(uint32_t(std::ceil(rounds)), 4u, kMaxBatch);
}

// "r7 legalise": a round's profiler label (appended, not "r" + std::to_string(r): GCC 12 warns falsely there).
std::string round_label(uint32_t r, const char* what) {
  std::string label = "r";
  label += std::to_string(r);
  label += what;
  return label;
}

// A host-visible, persistently mapped buffer: the counters of a batch are copied into it at the end of the
// batch's command buffer, so reading them costs no extra submission.
Buffer make_readback(const Context& ctx, VkDeviceSize bytes, void** mapped) {
  Buffer b;
  b.device = ctx.device;
  b.size = bytes;
  b.name = "cdt readback";
  VkBufferCreateInfo bi{};
  bi.sType = VK_STRUCTURE_TYPE_BUFFER_CREATE_INFO;
  bi.size = bytes;
  bi.usage = VK_BUFFER_USAGE_TRANSFER_DST_BIT;
  bi.sharingMode = VK_SHARING_MODE_EXCLUSIVE;
  VK_CHECK(vkCreateBuffer(ctx.device, &bi, nullptr, &b.buffer));
  VkMemoryRequirements req;
  vkGetBufferMemoryRequirements(ctx.device, b.buffer, &req);
  const VkMemoryPropertyFlags need = VK_MEMORY_PROPERTY_HOST_VISIBLE_BIT | VK_MEMORY_PROPERTY_HOST_COHERENT_BIT;
  uint32_t type = UINT32_MAX;
  for (VkMemoryPropertyFlags want : {need | VK_MEMORY_PROPERTY_HOST_CACHED_BIT, need})
    for (uint32_t i = 0; i < ctx.memory.memoryTypeCount && type == UINT32_MAX; ++i)
      if ((req.memoryTypeBits & (1u << i)) && (ctx.memory.memoryTypes[i].propertyFlags & want) == want) type = i;
  if (type == UINT32_MAX) throw DeviceError("no host-visible memory type on " + ctx.info.name);
  VkMemoryAllocateInfo ai{};
  ai.sType = VK_STRUCTURE_TYPE_MEMORY_ALLOCATE_INFO;
  ai.allocationSize = req.size;
  ai.memoryTypeIndex = type;
  VK_CHECK(vkAllocateMemory(ctx.device, &ai, nullptr, &b.memory));
  VK_CHECK(vkBindBufferMemory(ctx.device, b.buffer, b.memory, 0));
  VK_CHECK(vkMapMemory(ctx.device, b.memory, 0, bytes, 0, mapped));
  return b;
}

// insert_once's answer when the first walks found constraints through vertices (split_through): up to
// CDT_THROUGH_CAP (constraint, vertex) pairs, in no order.
struct ThroughVertices {
  std::vector<std::array<uint32_t, 2>> pairs;
};

std::string describe_error(uint32_t code, uint32_t c, std::span<const Edge> cons) {
  std::string which = "constraint " + std::to_string(c);
  if (c < cons.size()) which += " (" + std::to_string(cons[c][0]) + ", " + std::to_string(cons[c][1]) + ")";
  switch (code) {
    case CDT_ERR_VERTEX_ON_CONSTRAINT:
      return which + " passes through a vertex: split it there before insertion";
    case CDT_ERR_OUTSIDE:
      return which + " leaves the convex hull of the points";
    case CDT_ERR_NOT_AN_EDGE:
      return which + " crosses another constraint (resolve crossings first)";
    default:
      return which + ": the walk lost its way (the triangulation is not valid)";
  }
}

uint64_t directed(uint32_t x, uint32_t y) { return (uint64_t(x) << 32) | y; }

// Splits the pseudo-polygon chain[i..j] (the chain left of the base chain[i] -> chain[j]) into triangles: the
// apex is the chain vertex whose circle with the base holds no other chain vertex (Anglada's choice, with CGAL's
// perturbation for ties). Its triangle is empty and crosses no chain edge because every chain vertex sees the
// base (it is an endpoint of an edge that crossed the base), and both halves keep that property.
void split_pseudo_polygon(const HostTriangulation& h, const std::vector<uint32_t>& chain, size_t i, size_t j,
                          Triangles& out) {
  auto xy = [&](uint32_t v) { return pred::XY{h.xy[2 * v], h.xy[2 * v + 1]}; };
  if (j - i < 2) return;
  size_t apex = i + 1;
  for (size_t k = i + 2; k < j; ++k)
    if (pred::incircle_perturbed(xy(chain[i]), xy(chain[j]), xy(chain[apex]), xy(chain[k])) > 0) apex = k;
  out.push_back({chain[i], chain[j], chain[apex]});
  split_pseudo_polygon(h, chain, i, apex, out);
  split_pseudo_polygon(h, chain, apex, j, out);
}

// q on the line a-b and on b's side of a (cdt_walk.comp's on_b_side).
bool on_b_side(pred::XY a, pred::XY q, pred::XY b) {
  return b.x != a.x ? (q.x > a.x) == (b.x > a.x) : (q.y > a.y) == (b.y > a.y);
}

// The safety net (ConstraintOptions::stall_rounds): inserts the constraints that are not yet edges one at a time
// into host slots by retriangulating each one's cavity, the K + 1 triangles its segment crosses, as the K + 1
// triangles of the two pseudo-polygons on either side, written into the same slots. Exact predicates throughout.
// Returns how many constraints it inserted.
uint32_t insert_on_host(HostTriangulation& h, std::span<const Edge> cons) {
  const uint32_t slots = uint32_t(h.verts.size() / 3);
  auto xy = [&](uint32_t v) { return pred::XY{h.xy[2 * v], h.xy[2 * v + 1]}; };
  auto corner = [&](uint32_t t, uint32_t v) {
    for (uint32_t k = 0; k < 3; ++k)
      if (h.verts[3 * t + k] == v) return k;
    return 3u;
  };
  std::vector<uint32_t> vmap(h.xy.size() / 2, CDT_NEVER);
  for (uint32_t t = 0; t < slots; ++t)
    for (uint32_t k = 0; k < 3; ++k)
      if (h.verts[3 * t + k] != INF_VERTEX) vmap[h.verts[3 * t + k]] = t;
  std::vector<uint32_t> in_cavity(slots, CDT_NEVER);
  uint32_t inserted = 0;
  for (uint32_t c = 0; c < cons.size(); ++c) {
    const uint32_t a = cons[c][0], b = cons[c][1];
    if (a == b) continue;
    auto fail = [&](uint32_t code) { throw DeviceError(describe_error(code, c, cons)); };
    uint32_t t = vmap[a], k = corner(t, a);
    bool is_edge = false;
    for (uint32_t step = 0;; ++step) {
      if (step > 3 * slots) fail(CDT_ERR_LOST);
      const uint32_t v1 = h.verts[3 * t + (k + 1) % 3], v2 = h.verts[3 * t + (k + 2) % 3];
      if (v1 == b || v2 == b) {
        is_edge = true;
        break;
      }
      const int o1 = v1 == INF_VERTEX ? 1 : pred::orient2d(xy(a), xy(v1), xy(b));
      const int o2 = v2 == INF_VERTEX ? -1 : pred::orient2d(xy(a), xy(v2), xy(b));
      // A neighbour of a on the open segment, as in cdt_walk.comp.
      if ((o1 == 0 && on_b_side(xy(a), xy(v1), xy(b))) || (o2 == 0 && on_b_side(xy(a), xy(v2), xy(b))))
        fail(CDT_ERR_VERTEX_ON_CONSTRAINT);
      if (v1 != INF_VERTEX && v2 != INF_VERTEX && o1 > 0 && o2 < 0) break;
      const uint32_t code = h.nbrs[3 * t + (k + 1) % 3];
      t = NBR_TRI(code);
      k = (NBR_EDGE(code) + 1) % 3;
    }
    if (is_edge) continue;
    ++inserted;
    // The cavity, and its two chains from a to b: left of a->b (first v2) and right of it (first v1).
    std::vector<uint32_t> cavity = {t};
    std::vector<uint32_t> left = {a, h.verts[3 * t + (k + 2) % 3]}, right = {a, h.verts[3 * t + (k + 1) % 3]};
    for (uint32_t ke = k;;) {
      const uint32_t code = h.nbrs[3 * t + ke], u = NBR_TRI(code), ku = NBR_EDGE(code), w = h.verts[3 * u + ku];
      if (w == INF_VERTEX) fail(CDT_ERR_OUTSIDE);
      cavity.push_back(u);
      if (w == b) break;
      const int s = pred::orient2d(xy(a), xy(b), xy(w));
      if (s == 0) fail(CDT_ERR_VERTEX_ON_CONSTRAINT);
      (s > 0 ? left : right).push_back(w);
      ke = s > 0 ? (ku + 1) % 3 : (ku + 2) % 3;
      t = u;
    }
    left.push_back(b);
    right.push_back(b);
    for (uint32_t x : cavity) in_cavity[x] = c;
    std::unordered_map<uint64_t, uint32_t> outside;  // boundary edge, directed as in the cavity -> neighbour
    for (uint32_t x : cavity)
      for (uint32_t e = 0; e < 3; ++e) {
        const uint32_t code = h.nbrs[3 * x + e];
        if (in_cavity[NBR_TRI(code)] != c)
          outside[directed(h.verts[3 * x + (e + 1) % 3], h.verts[3 * x + (e + 2) % 3])] = code;
      }
    Triangles made;
    split_pseudo_polygon(h, left, 0, left.size() - 1, made);  // left chain: left of a -> b
    std::reverse(right.begin(), right.end());
    split_pseudo_polygon(h, right, 0, right.size() - 1, made);  // right chain reversed: left of b -> a
    if (made.size() != cavity.size()) fail(CDT_ERR_LOST);
    std::unordered_map<uint64_t, uint32_t> here;
    for (size_t i = 0; i < made.size(); ++i)
      for (uint32_t e = 0; e < 3; ++e) {
        h.verts[3 * cavity[i] + e] = made[i][e];
        here[directed(made[i][(e + 1) % 3], made[i][(e + 2) % 3])] = NBR(cavity[i], e);
      }
    for (size_t i = 0; i < made.size(); ++i)
      for (uint32_t e = 0; e < 3; ++e) {
        const uint32_t x = made[i][(e + 1) % 3], y = made[i][(e + 2) % 3];
        auto inner = here.find(directed(y, x));
        if (inner != here.end()) {
          h.nbrs[3 * cavity[i] + e] = inner->second;
          continue;
        }
        auto outer = outside.find(directed(x, y));
        if (outer == outside.end()) fail(CDT_ERR_LOST);
        h.nbrs[3 * cavity[i] + e] = outer->second;
        h.nbrs[3 * NBR_TRI(outer->second) + NBR_EDGE(outer->second)] = NBR(cavity[i], e);
        vmap[x] = cavity[i];
      }
  }
  return inserted;
}

}  // namespace

ConstraintInserter::ConstraintInserter(const Context& ctx, const Primitives& prims)
    : ctx_(ctx),
      prims_(prims),
      vertex_map_(create_pass(ctx, {"cdt_vertex_map", 2, sizeof(CdtSlotsPush)})),
      walk_(create_pass(ctx, {"cdt_walk", 16, sizeof(CdtWalkPush)})),
      args_(create_pass(ctx, {"cdt_args", 4, sizeof(CdtArgsPush)})),
      insert_claim_(create_pass(ctx, {"cdt_insert_claim", 9, sizeof(CdtRoundPush)})),
      insert_flip_(create_pass(ctx, {"cdt_insert_flip", 11, sizeof(CdtRoundPush)})),
      fix_(create_pass(ctx, {"cdt_fix", 5, sizeof(CdtRoundPush)})),
      cavity_(create_pass(ctx, {"cdt_cavity", 16, sizeof(CdtWalkPush)})),
      cavity_fix_(create_pass(ctx, {"cdt_cavity_fix", 5, sizeof(CdtRoundPush)})),
      legal_seed_(create_pass(ctx, {"cdt_legal_seed", 6, sizeof(CdtSlotsPush)})),
      legal_claim_(create_pass(ctx, {"cdt_legal_claim", 9, sizeof(CdtRoundPush)})),
      legal_flip_(create_pass(ctx, {"cdt_legal_flip", 13, sizeof(CdtRoundPush)})) {}

// Device buffers kept between calls, and the mapped readback buffer.
struct ConstraintInserter::Scratch {
  BufferCache buffers;
  Buffer readback;
  void* mapped = nullptr;
};

// The constraints of one insert_once: a list held elsewhere, or one held here, or a held list with some entries
// replaced and pieces appended, made on the host only when asked for (a split pass's list, whose device copy is
// patched on the device: the host's serves only an error's message, the host fallback and a further split).
class ConstraintInserter::EdgeList {
 public:
  explicit EdgeList(std::span<const Edge> held) : list_(held) {}
  explicit EdgeList(RawVector<Edge>&& own) : own_(std::move(own)), list_(own_) {}
  EdgeList(std::span<const Edge> base, std::vector<std::pair<uint32_t, Edge>> replaced, std::vector<Edge> appended)
      : list_(base), replaced_(std::move(replaced)), appended_(std::move(appended)), pending_(true) {}

  size_t size() const { return list_.size() + (pending_ ? appended_.size() : 0); }
  const std::vector<std::pair<uint32_t, Edge>>& replaced() const { return replaced_; }
  const std::vector<Edge>& appended() const { return appended_; }

  // The list itself, made on first use.
  std::span<const Edge> span() const {
    if (pending_) {
      own_ = made();
      list_ = own_;
      pending_ = false;
    }
    return list_;
  }
  // A patched list made whole, in a vector of its own (copied on all cores: ~20 ms for a tile's 31M at 1B points).
  RawVector<Edge> made() const {
    RawVector<Edge> out;  // unwritten: zeroing 250 MB on one core took longer than the copy
    out.reserve(size());
    resize_unwritten(out, list_.size());
    copy_on_all_cores(list_.data(), list_.size(), out.data());
    for (const auto& [c, e] : replaced_) out[c] = e;
    out.insert(out.end(), appended_.begin(), appended_.end());
    return out;
  }

 private:
  mutable RawVector<Edge> own_;
  mutable std::span<const Edge> list_;
  std::vector<std::pair<uint32_t, Edge>> replaced_;
  std::vector<Edge> appended_;
  mutable bool pending_ = false;
};

ConstraintInserter::~ConstraintInserter() = default;

void ConstraintInserter::recycle(ConstrainedEdges&& edges) const {
  if (cache && edges.flags.buffer) cache->give(kFlagsKey, std::move(edges.flags));
}

void ConstraintInserter::release() const { scratch_.reset(); }

void check_constraint_ids(std::span<const Edge> constraints, uint64_t num_points) {
  // On all cores: a 1B-point tile's 31M constraints took ~30 ms on one.
  const size_t bad = tbb::parallel_reduce(
      tbb::blocked_range<size_t>(0, constraints.size(), 1 << 16), constraints.size(),
      [&](const tbb::blocked_range<size_t>& r, size_t first) {
        for (size_t i = r.begin(); i < r.end() && i < first; ++i)
          if (constraints[i][0] >= num_points || constraints[i][1] >= num_points) return i;
        return first;
      },
      [](size_t a, size_t b) { return std::min(a, b); });
  if (bad < constraints.size())
    throw std::invalid_argument("insert_constraints: constraint " + std::to_string(bad) + " has a vertex index past " +
                                std::to_string(num_points) + " points");
}

ConstrainedEdges ConstraintInserter::insert(GpuTriangulation& tri, std::span<const Edge> constraints,
                                            ConstraintStats* stats, const ConstraintOptions& options,
                                            const Buffer* uploaded) const {
  if (!options.unresolved) return insert_once(tri, EdgeList(constraints), stats, options, false, uploaded);
  // A constraint through vertices is split at them and the whole is inserted again: the walks that find them
  // are the first submission's, before anything flips, so the triangulation is still the one given. One pass
  // finds them all unless there are more than CDT_THROUGH_CAP; after kPasses the resolve splits them instead.
  constexpr int kPasses = 16;
  // The first split's list is the given one patched on the device (the split constraints' first pieces in
  // their places, the other pieces after the end) when it replaces at most this many: in a CLI run at 1B points
  // a tile's few splits (1-5) took 16-141 ms of host work and ~40 ms of upload while the tile held its device,
  // a copy of its 31M constraints made on cores busy staging other tiles, then sent whole.
  constexpr size_t kPatchedAtMost = 1024;
  ConstraintOptions checked = options;
  checked.unresolved = false;
  std::optional<EdgeList> list;
  list.emplace(constraints);
  const Buffer* on_device = uploaded;  // the list's copy on the device, when there is one
  std::vector<std::array<uint32_t, 3>> split;
  for (int pass = 0;; ++pass) {
    const auto t_pass = std::chrono::steady_clock::now();
    try {
      ConstrainedEdges r = insert_once(tri, *list, stats, checked, pass < kPasses, on_device);
      r.split = std::move(split);
      return r;
    } catch (ThroughVertices& t) {
      const double walked_ms = ms_since(t_pass);
      const auto t_split = std::chrono::steady_clock::now();
      // Per constraint, its vertices in (x, y) order, which is their order along it from a (a < b). A split
      // constraint's first piece takes its place and the others go after the end: order does not matter here,
      // and a sort of the list took ~0.45 s of the device's time.
      std::sort(t.pairs.begin(), t.pairs.end());
      const std::span<const Edge> was = pass == 0 ? constraints : list->span();
      std::vector<std::pair<uint32_t, Edge>> replaced;
      std::vector<Edge> appended, made;
      for (size_t i = 0; i < t.pairs.size();) {
        const uint32_t c = t.pairs[i][0];
        const auto [a, b] = was[c];
        uint32_t from = a;
        for (; i < t.pairs.size() && t.pairs[i][0] == c; ++i) {
          const uint32_t v = t.pairs[i][1];
          split.push_back({from, b, v});
          made.push_back({from, v});
          if (from == a)
            replaced.push_back({c, made.back()});
          else
            appended.push_back(made.back());
          from = v;
        }
        made.push_back({from, b});
        appended.push_back(made.back());
      }
      // Equal pieces (collinear overlaps) merge, and only then is the whole list sorted.
      std::sort(made.begin(), made.end());
      // A split's pieces are looked up in the list: whether it is sorted, the caller's word for the given one.
      const bool sorted = (pass == 0 && options.sorted) || std::is_sorted(std::execution::par, was.begin(), was.end());
      bool sort_all = !sorted || std::adjacent_find(made.begin(), made.end()) != made.end();
      for (size_t k = 0; k < made.size() && !sort_all; ++k)
        sort_all = std::binary_search(was.begin(), was.end(), made[k]);
      const uint64_t m = was.size();
      EdgeList next(was, std::move(replaced), std::move(appended));
      const Buffer* next_on_device = nullptr;
      if (sort_all) {
        RawVector<Edge> all = next.made();
        tbb::parallel_sort(all.begin(), all.end());
        all.erase(std::unique(all.begin(), all.end()), all.end());
        list.emplace(std::move(all));
      } else if (pass == 0 && next.replaced().size() <= kPatchedAtMost) {
        if (!scratch_) scratch_ = std::make_unique<Scratch>();
        BufferCache& buffers = cache ? *cache : scratch_->buffers;
        const Buffer& from = on_device ? *on_device : buffers.get(ctx_, kConstraintsKey, m * 8);
        const Buffer& to = buffers.get(ctx_, on_device ? kConstraintsKey : kSplitKey, next.size() * 8);
        Recorder rec(ctx_);
        rec.copy(from, to, m * 8);
        for (const auto& [c, e] : next.replaced()) rec.update(to, uint64_t(c) * 8, &e, 8);
        const std::vector<Edge>& tail = next.appended();
        for (size_t k = 0; k < tail.size(); k += 8192)
          rec.update(to, (m + k) * 8, &tail[k], std::min<size_t>(8192, tail.size() - k) * 8);
        rec.submit();
        next_on_device = &to;
        list.emplace(std::move(next));
      } else {
        RawVector<Edge> all = next.made();  // `was` may be the list's own: made whole before it is replaced
        list.emplace(std::move(all));
      }
      on_device = next_on_device;
      spdlog::debug("constraints: pass {}: {} constraints through {} vertices split in {:.0f} ms, after {:.0f} ms{}",
                    pass + 1, made.size() - t.pairs.size(), t.pairs.size(), ms_since(t_split), walked_ms,
                    sort_all ? " (sorted, equal pieces merged)" : on_device ? " (patched on the device)" : "");
    } catch (const TooLarge&) {
      throw;
    } catch (const VulkanError&) {
      throw;
    } catch (const DeviceError& e) {
      throw UnresolvedTile(e.what());
    }
  }
}

ConstrainedEdges ConstraintInserter::insert_once(GpuTriangulation& tri, const EdgeList& constraints,
                                                 ConstraintStats* stats, const ConstraintOptions& options,
                                                 bool split_through, const Buffer* uploaded) const {
  const uint32_t m = static_cast<uint32_t>(constraints.size());
  const uint32_t slots = tri.num_slots;
  const bool fixed_slots = options.layout == ConstraintOptions::Layout::FixedSlots;
  const uint32_t one_per_constraint = options.flipping == ConstraintOptions::Flipping::OnePerConstraint ? 1u : 0u;
  const uint32_t domain = options.domain_index ? 1u : 0u;
  const bool cavities = options.cavities && options.domain_index && !fixed_slots && !one_per_constraint;
  const uint32_t max_groups = ctx_.props.limits.maxComputeWorkGroupCount[0];
  const uint32_t max_steps = 3 * slots + 64;
  if (constraints.size() >= CDT_NEVER) throw std::invalid_argument("insert_constraints: too many constraints");
  if (!uploaded) check_constraint_ids(constraints.span(), tri.num_points);  // an uploaded list was checked as staged

  if (!scratch_) scratch_ = std::make_unique<Scratch>();
  Scratch& sc = *scratch_;
  const size_t readback_words = std::max<size_t>(CDT_CTL_WORDS + 2 * kMaxBatch, 1 + 2 * CDT_THROUGH_CAP);
  if (!sc.readback.buffer) sc.readback = make_readback(ctx_, readback_words * 4, &sc.mapped);
  const uint32_t* rb = static_cast<const uint32_t*>(sc.mapped);
  uint64_t needed = 0, table_bytes = 0;  // what this call uses (the cache may hold more from earlier calls)
  BufferCache& buffers = cache ? *cache : sc.buffers;
  auto get = [&](const char* key, uint64_t bytes, const char* label = "") -> const Buffer& {
    needed += bytes;
    return buffers.get(ctx_, key, bytes, label);
  };

  ConstrainedEdges result;
  result.num_slots = slots;
  // From the cache: what recycle() gave back.
  result.flags = cache ? cache->take(ctx_, kFlagsKey, uint64_t(slots) * 4)
                       : create_buffer(ctx_, uint64_t(slots) * 4, kFlagsKey);

  // Uploaded as they are (two uint32 each): a copy into a fresh array was ~0.2 s on one core per 31M.
  static_assert(sizeof(Edge) == 8);
  if (uploaded && uploaded->size < uint64_t(m) * 8)
    throw std::invalid_argument("insert_constraints: the uploaded constraints' buffer is too small");
  if (uploaded) needed += uploaded->size;
  const Buffer& cons = uploaded ? *uploaded : get(kConstraintsKey, uint64_t(m) * 8);
  if (m && !uploaded) upload(ctx_, cons, constraints.span().data(), uint64_t(m) * 8);
  const Buffer& start = get("cdt start slots", uint64_t(m) * 4);
  const Buffer& counts = get("cdt crossing counts", uint64_t(m) * 4);
  const Buffer& offsets = get("cdt row offsets", uint64_t(m) * 4);
  const Buffer& cache_base = get("cdt row cache base", uint64_t(m) * 4);
  const Buffer& cache_cap = get("cdt row cache room", uint64_t(m) * 4);
  const Buffer& first_row = get("cdt first candidate", uint64_t(m) * 8);
  // Per-point and per-slot scratch under the shared keys (the Delaunay build's, when the cache is shared).
  // The Delaunay build's vertex slots when it left them (kept up to date here), else a vertex map of our own.
  const bool given_map = tri.vertex_slots.buffer != VK_NULL_HANDLE;
  const Buffer& vmap = given_map ? tri.vertex_slots : get(kPoints4[0], uint64_t(tri.num_points) * 4, "cdt vertex map");
  const Buffer& owner = get(kSlots8[0], uint64_t(slots) * 8, "cdt owners");
  const Buffer& claim = get(kSlots8[1], uint64_t(slots) * 8, "cdt claims");
  const Buffer& stamp = get(kSlots4[0], uint64_t(slots) * 4, "cdt flip stamps");
  const Buffer& partner = get(kSlots4[1], uint64_t(slots) * 4, "cdt flip partners");
  const Buffer& remap = get(kSlots12[0], uint64_t(slots) * 12, "cdt edge remap");
  const Buffer& qstamp = get(kSlots4[2], uint64_t(slots) * 4, "cdt queue stamps");
  const Buffer& flips = get("cdt flip list", (uint64_t(slots) / 2 + 1) * 8);
  const Buffer& ctl = get("cdt control", (split_through ? CDT_CTL_ALL_WORDS : CDT_CTL_WORDS) * 4);
  const Buffer& stat = get("cdt round stats", uint64_t(kMaxBatch) * 8);
  const Buffer& cand = get(kSlots12[1], uint64_t(slots) * 12, "cdt legalise candidates");
  const Buffer* queue[2] = {&get(kSlots4[3], uint64_t(slots) * 4, "cdt queue 0"),
                            &get(kSlots4[4], uint64_t(slots) * 4, "cdt queue 1")};
  const Buffer* table = nullptr;  // sized after the first count

  StageClock clock;
  ConstraintStats st;
  const bool detail = options.profile_kernels;
  // With options.profile_kernels: timestamps around one kernel (or a round, `name` then as given).
  auto timed = [&](Profiler& prof, Recorder& rec, const std::string& name, auto&& record) {
    if (detail) prof.begin(rec, name);
    record();
    if (detail) prof.end(rec);
  };
  auto stages_for = [&](uint32_t batch, uint32_t per_round) { return detail ? (per_round + 1) * batch + 8 : 3 * batch + 2; };
  uint32_t round = 1;

  // Records the copy of the counters (and `rounds` rounds of statistics) into the mapped readback buffer.
  auto copy_back = [&](Recorder& rec, uint32_t rounds) {
    rec.copy(ctl, sc.readback, CDT_CTL_WORDS * 4);
    if (rounds) rec.copy(stat, sc.readback, uint64_t(rounds) * 8, 0, CDT_CTL_WORDS * 4);
  };
  // After the submission: the counters, or the error a pass reported.
  auto read_ctl = [&] {
    std::vector<uint32_t> c(rb, rb + CDT_CTL_WORDS);
    if (c[CDT_CTL_ERROR])
      throw DeviceError(describe_error(c[CDT_CTL_ERROR], c[CDT_CTL_ERROR_CONS], constraints.span()));
    return c;
  };
  auto read_stats = [&](uint32_t rounds) { return std::vector<uint32_t>(rb + CDT_CTL_WORDS, rb + CDT_CTL_WORDS + 2 * rounds); };
  const Buffer* row_cache = nullptr;
  auto walk = [&](Recorder& rec, uint32_t mode, uint32_t r, uint32_t capacity, uint32_t stride, bool use_cache = true) {
    // Bound but unused before they exist.
    const Buffer& rows = table ? *table : result.flags;
    const Buffer& cached = row_cache ? *row_cache : result.flags;
    CdtWalkPush push{m,      mode, r, capacity, max_steps, stride, row_cache && use_cache ? 1u : 0u,
                     domain, split_through ? 1u : 0u};
    rec.dispatch_groups(walk_, {tri.points, tri.verts, tri.nbrs, cons, start, counts, offsets, rows, owner,
                                result.flags, vmap, partner, ctl, cached, cache_base, cache_cap},
                        push, groups(m));
  };
  auto args = [&](Recorder& rec, uint32_t mode, uint32_t r, uint32_t slot, uint32_t capacity, uint32_t stride) {
    CdtArgsPush push{mode, m, capacity, r, slot, max_groups, stride};
    rec.dispatch(args_, {counts, offsets, ctl, stat}, push, 1);
  };
  auto vertex_map = [&](Recorder& rec) {
    rec.fill(vmap, 0xFFFFFFFFu);
    rec.dispatch_groups(vertex_map_, {tri.verts, vmap}, CdtSlotsPush{slots, 0, 0}, groups(slots));
  };
  auto fix = [&](Recorder& rec, uint32_t r) {
    CdtRoundPush push{r, 0, 0};
    rec.dispatch_indirect(fix_, {tri.nbrs, remap, stamp, flips, ctl}, &push, ctl, CDT_CTL_ARGS_FLIPS * 4);
  };

  // 1. Vertex map and start slots; one counting walk sizes the intersected-edge table.
  uint32_t crossed = 0, stride = 0;
  uint64_t capacity = 0;
  {
    Recorder rec(ctx_);
    Profiler prof(ctx_, 4);
    prof.begin(rec, "vertex map");
    for (const Buffer* b : {&owner, &claim, &first_row}) rec.fill(*b, 0xFFFFFFFFu);
    for (const Buffer* b : {&stamp, &qstamp}) rec.fill(*b, CDT_NEVER);
    rec.fill(result.flags, 0);
    rec.fill(ctl, 0);
    if (!given_map) vertex_map(rec);
    walk(rec, CDT_WALK_INIT, round, 0, 0);
    prof.end(rec);
    prof.begin(rec, "crossing detection");
    walk(rec, CDT_WALK_COUNT, round, 0, 0);
    if (!fixed_slots && m > 0) {  // the row cache's layout: the first counts, compacted; also round 1's offsets
      prims_.exclusive_scan(rec, counts, cache_base, m);
      rec.copy(counts, cache_cap, uint64_t(m) * 4);
      rec.copy(cache_base, offsets, uint64_t(m) * 4);
    }
    prof.end(rec);
    copy_back(rec, 0);
    rec.submit();
    clock.add(prof);
    if (split_through && rb[CDT_CTL_ERROR] == CDT_ERR_VERTEX_ON_CONSTRAINT) {
      // Only walks met trouble, and they flip nothing: the pairs they found, for insert() to split.
      Recorder pairs(ctx_);
      pairs.copy(ctl, sc.readback, (1 + 2 * CDT_THROUGH_CAP) * 4, CDT_CTL_THROUGH * 4, 0);
      pairs.submit();
      ThroughVertices t;
      const uint32_t found = std::min(rb[0], CDT_THROUGH_CAP);
      for (uint32_t i = 0; i < found; ++i) t.pairs.push_back({rb[1 + 2 * i], rb[2 + 2 * i]});
      recycle(std::move(result));  // for the next pass: freeing and making 1 GB of flags took ~0.1 s a tile
      throw t;
    }
    std::vector<uint32_t> c = read_ctl();
    crossed = c[CDT_CTL_CROSSED];
    stride = c[CDT_CTL_MAXK];
  }
  st.crossed_edges = crossed;
  bool fresh_table = false;
  auto make_table = [&] {
    capacity = fixed_slots ? uint64_t(m) * stride : uint64_t(crossed) + crossed / 2 + 1024;
    if (capacity >= CDT_NEVER)
      throw TooLarge("insert_constraints: intersected-edge table too large", double(capacity), double(CDT_NEVER));
    table_bytes = std::max(table_bytes, capacity * sizeof(CdtCross));
    table = &buffers.get(ctx_, "cdt intersected-edge table", capacity * sizeof(CdtCross));
    fresh_table = true;
  };
  // The row cache: each constraint's first count plus CDT_CACHE_SLACK rows, so the second stage of the layout
  // copies rows instead of walking again (a round lasts as long as its longest walk).
  if (!fixed_slots && crossed > 0) {
    const uint64_t rows = uint64_t(crossed) + uint64_t(CDT_CACHE_SLACK) * m;
    needed += rows * 8;
    row_cache = &buffers.get(ctx_, "cdt row cache", rows * 8);
  }
  st.longest_crossing = stride;

  // 2. Insertion rounds: crossing detection, then adaptive parallel flipping, until no constraint crosses an edge.
  bool legalise_all = options.legalise_all;
  bool host_rewrote = false;  // the safety net rewrote slots: the constrained bits are marked again
  if (crossed > 0) {
    make_table();
    uint32_t fewest = UINT32_MAX, stalled = 0, before = 0, last = crossed;
    uint32_t batch = std::clamp(options.rounds_per_submit, 1u, kMaxBatch);
    for (bool done = false; !done;) {
      Recorder rec(ctx_);
      Profiler prof(ctx_, stages_for(batch, 12));
      const uint32_t cap = static_cast<uint32_t>(capacity), s = fixed_slots ? stride : 0;
      // Round 1 of the prefix-sum layout reuses the first count (start, counts, the crossed total in ctl) and
      // its scan (offsets): nothing flipped since.
      const bool reuse_first_count = round == 1 && !fixed_slots;
      if (!reuse_first_count) rec.fill(ctl, 0);  // clears the overflow flag; per-round counters are zero anyway
      if (fresh_table && fixed_slots) rec.fill(*table, 0xFFFFFFFFu);  // every row empty
      fresh_table = false;
      for (uint32_t b = 0; b < batch; ++b) {
        const uint32_t r = round + b;
        const bool first = reuse_first_count && b == 0;
        if (detail) prof.begin(rec, round_label(r, " insert"));
        prof.begin(rec, "crossing detection");
        if (!first) timed(prof, rec, "k:walk count", [&] { walk(rec, CDT_WALK_COUNT, r, cap, s); });
        prof.end(rec);
        prof.begin(rec, "prefix-sum layout");  // stage 2 of the table: offsets, then the rows written compactly
        if (!fixed_slots && !first)
          timed(prof, rec, "k:scan", [&] { prims_.exclusive_scan(rec, counts, offsets, m); });
        timed(prof, rec, "k:args table", [&] { args(rec, CDT_ARGS_INSERT, r, b, cap, s); });
        // Round 1's rows are not in the row cache (the first count ran before it existed): walk them.
        if (!fixed_slots) timed(prof, rec, "k:walk write", [&] { walk(rec, CDT_WALK_WRITE, r, cap, 0, !first); });
        prof.end(rec);
        prof.begin(rec, "flipping");
        CdtRoundPush push{r, one_per_constraint, domain};
        if (cavities)  // the legalisation candidates are free until then: they hold the cavity fix list
          timed(prof, rec, "k:cavity", [&] {
            CdtWalkPush cp{m, 0, r, cap, max_steps, 0, 0, domain, 0};
            rec.dispatch_groups(cavity_, {tri.points, tri.verts, tri.nbrs, cons, start, counts, offsets, *table, owner,
                                          result.flags, remap, stamp, partner, vmap, cand, ctl},
                                cp, groups(m));
          });
        timed(prof, rec, "k:insert claim", [&] {
          rec.dispatch_indirect(insert_claim_,
                                {tri.points, tri.verts, tri.nbrs, *table, owner, claim, ctl, first_row, result.flags},
                                &push, ctl,
                                CDT_CTL_ARGS_TABLE * 4);
        });
        timed(prof, rec, "k:insert flip", [&] {
          rec.dispatch_indirect(insert_flip_, {tri.verts, tri.nbrs, *table, claim, result.flags, remap, stamp,
                                               partner, flips, ctl, first_row},
                                &push, ctl, CDT_CTL_ARGS_TABLE * 4);
        });
        timed(prof, rec, "k:args flips", [&] { args(rec, CDT_ARGS_FLIPS, r, b, cap, s); });
        timed(prof, rec, "k:insert fix", [&] { fix(rec, r); });
        if (cavities)
          timed(prof, rec, "k:cavity fix", [&] {
            rec.dispatch_indirect(cavity_fix_, {tri.nbrs, remap, stamp, cand, ctl}, &push, ctl,
                                  CDT_CTL_ARGS_FIXES * 4);
          });
        prof.end(rec);
        if (detail) prof.end(rec);
      }
      copy_back(rec, batch);
      rec.submit();
      clock.add(prof);
      std::vector<uint32_t> c = read_ctl();
      std::vector<uint32_t> per_round = read_stats(batch);
      const bool overflow = c[CDT_CTL_OVERFLOW] != 0;
      for (uint32_t b = 0; b < batch && !done; ++b) {
        const uint32_t found = per_round[2 * b], flipped = per_round[2 * b + 1];
        if (found == 0) {
          done = true;
          break;
        }
        ++st.flip_rounds;
        st.rounds.push_back({found, flipped});
        before = last;
        last = found;
        crossed = std::max(crossed, found);
        if (found < fewest) {
          fewest = found;
          stalled = 0;
        } else {
          ++stalled;
        }
        if (flipped == CDT_NEVER) continue;  // the table was too small this round
        st.insertion_flips += flipped;
        // The smallest unfinished constraint owns its whole domain, and some edge it crosses has a strictly
        // convex quadrilateral, so a round without a flip means the input broke a requirement.
        if (flipped == 0)
          throw DeviceError("insert_constraints: round " + std::to_string(round + b) + " found " +
                            std::to_string(found) + " crossed edges and no flip (degenerate input?)");
      }
      round += batch;
      if (!done && (stalled >= options.stall_rounds || st.flip_rounds >= options.flip_round_limit)) {
        HostTriangulation host = download_host(ctx_, tri);
        st.fallback_constraints = insert_on_host(host, constraints.span());
        upload(ctx_, tri.verts, host.verts.data(), host.verts.size() * 4);
        upload(ctx_, tri.nbrs, host.nbrs.data(), host.nbrs.size() * 4);
        legalise_all = true;
        host_rewrote = true;
        done = true;
      }
      if (overflow && !done) {
        stride = std::max(stride, c[CDT_CTL_MAXK]);
        make_table();
      }
      batch = predict_rounds(before, last);
    }
  }

  // 3. Which edges are constraints: each count walk that found its constraint an edge set its bits, and flips
  //    carry them along; after the host safety net they are marked again.
  if (host_rewrote) {
    Recorder rec(ctx_);
    Profiler prof(ctx_, 1);
    prof.begin(rec, "mark constrained");
    rec.fill(result.flags, 0);
    vertex_map(rec);
    walk(rec, CDT_WALK_MARK, round, 0, 0);
    prof.end(rec);
    copy_back(rec, 0);
    rec.submit();
    clock.add(prof);
    read_ctl();
  }

  // 4. Legalisation rounds: flip every unconstrained edge that fails the perturbed incircle test.
  {
    bool seeded = false;
    uint32_t batch = std::clamp(options.rounds_per_submit, 1u, kMaxBatch), before = 0, last = 0;
    for (bool done = false; !done;) {
      Recorder rec(ctx_);
      Profiler prof(ctx_, stages_for(batch, 6));
      if (!seeded) {
        prof.begin(rec, "legalise seed");
        CdtSlotsPush push{slots, round, legalise_all ? 1u : 0u};
        rec.dispatch_groups(legal_seed_, {tri.verts, stamp, qstamp, *queue[round & 1], ctl, partner}, push,
                            groups(slots));
        prof.end(rec);
        seeded = true;
      }
      for (uint32_t b = 0; b < batch; ++b) {
        const uint32_t r = round + b;
        const Buffer& q = *queue[r & 1];
        const Buffer& next = *queue[(r + 1) & 1];
        CdtRoundPush push{r, 0, 0};
        prof.begin(rec, "legalise");
        if (detail) prof.begin(rec, round_label(r, " legalise"));
        timed(prof, rec, "k:args queue", [&] { args(rec, CDT_ARGS_QUEUE, r, b, 0, 0); });
        timed(prof, rec, "k:legal claim", [&] {
          rec.dispatch_indirect(legal_claim_,
                                {tri.points, tri.verts, tri.nbrs, result.flags, qstamp, q, claim, cand, ctl}, &push,
                                ctl, CDT_CTL_ARGS_QUEUE * 4);
        });
        timed(prof, rec, "k:legal flip", [&] {
          rec.dispatch_indirect(legal_flip_,
                                {tri.verts, tri.nbrs, result.flags, remap, stamp, partner, qstamp, q, next, claim,
                                 cand, flips, ctl},
                                &push, ctl, CDT_CTL_ARGS_QUEUE * 4);
        });
        timed(prof, rec, "k:args flips", [&] { args(rec, CDT_ARGS_FLIPS, r, b, 0, 0); });
        timed(prof, rec, "k:legal fix", [&] { fix(rec, r); });
        if (detail) prof.end(rec);
        prof.end(rec);
      }
      copy_back(rec, batch);
      rec.submit();
      clock.add(prof);
      read_ctl();
      std::vector<uint32_t> per_round = read_stats(batch);
      for (uint32_t b = 0; b < batch; ++b) {
        if (per_round[2 * b] == 0) {
          done = true;
          break;
        }
        ++st.legalise_rounds;
        st.legalise_flips += per_round[2 * b + 1];
        st.legalise_log.push_back({per_round[2 * b], per_round[2 * b + 1]});
        before = last;
        last = per_round[2 * b];
      }
      round += batch;
      if (round > options.max_rounds)
        throw DeviceError("insert_constraints: more than " + std::to_string(options.max_rounds) + " rounds");
      batch = predict_rounds(before, last);  // queues shrink geometrically too
    }
  }

  if (stats) {
    st.stage_ms = std::move(clock.stages);
    st.peak_device_bytes =
        tri.points.size + tri.verts.size + tri.nbrs.size + tri.vertex_slots.size + result.flags.size +
        sc.readback.size + needed + table_bytes;
    *stats = std::move(st);
  }
  return result;
}

ConstrainedEdges insert_constraints(const Context& ctx, GpuTriangulation& tri, std::span<const Edge> constraints,
                                    ConstraintStats* stats, const ConstraintOptions& options) {
  Primitives prims(ctx);
  ConstraintInserter inserter(ctx, prims);
  return inserter.insert(tri, constraints, stats, options);
}

std::vector<Edge> download_constrained_edges(const Context& ctx, const GpuTriangulation& tri,
                                             const ConstrainedEdges& edges) {
  const uint32_t slots = std::min(tri.num_slots, edges.num_slots);
  std::vector<uint32_t> flags = download_vector<uint32_t>(ctx, edges.flags, slots);
  std::vector<uint32_t> verts = download_vector<uint32_t>(ctx, tri.verts, size_t(slots) * 3);
  std::vector<Edge> out;
  for (uint32_t t = 0; t < slots; ++t)
    for (uint32_t k = 0; k < 3; ++k)
      if ((flags[t] >> k) & 1u) {
        uint32_t a = verts[3 * t + (k + 1) % 3], b = verts[3 * t + (k + 2) % 3];
        out.push_back({std::min(a, b), std::max(a, b)});
      }
  std::sort(out.begin(), out.end());
  out.erase(std::unique(out.begin(), out.end()), out.end());
  return out;
}

}  // namespace cdtgpu::gpu
