// The GPU Delaunay driver: build() reads as the algorithm (first triangle, then rounds of insert + flip until
// every point is a vertex); each step records its passes (shaders/dt_*.comp) into the build's one command
// buffer, submitted once per round (plus once per extra batch of flip passes). The method, its invariants and
// why the result equals CGAL's: docs/gpu-delaunay.md.
#include "gpu/delaunay.hpp"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <array>
#include <chrono>
#include <cstring>
#include <map>
#include <optional>

#include "core/predicates.hpp"
#include "gpu/check.hpp"
#include "gpu/profiler.hpp"
#include "shaders/layout_dt.h"

namespace cdtgpu::gpu {

using namespace layout;

namespace {

// The build's own buffers that a caller's cache keeps between builds (tiles): taken by kept(), given back in
// number_back under the same keys.
constexpr const char* kPtsKey = "dt pts";
constexpr const char* kPermKey = "dt perm";
constexpr const char* kReduceKey = "dt reduce";
constexpr const char* kGrantedKey = "dt granted";
constexpr const char* kGrantedAtKey = "dt granted positions";
constexpr const char* kRanksKey = "dt ranks";
constexpr const char* kCountersKey = "dt counters";
constexpr const char* kArgsKey = "dt args";
constexpr const char* kScanSumsKey = "dt scan sums";

uint64_t groups(uint64_t n) { return (n + DT_WG - 1) / DT_WG; }

uint32_t slot_capacity(uint32_t n) { return 2 * n - 2; }  // 2(n + 1) - 4: a sphere with n + 1 vertices

// Flip passes per submit whose list length profile_kernels logs (later ones are logged with length 0).
constexpr uint32_t kPassLog = 512;

// Words of a bit set over n slots or list positions.
uint64_t rank_words(uint32_t n) { return n / 32 + 2; }
// Words of the ranks over n list positions (shaders/dt_rank.comp): a prefix per bit-set word, the total, and
// a prefix per tile of DT_WG words.
uint64_t ranks_words(uint32_t n) { return rank_words(n) + 1 + (rank_words(n) + DT_WG - 1) / DT_WG; }

// ExactChecks::adaptive inlines the exact stage in a round's flip checks when the last round needed it for
// fewer slots than this: uniform data never does; a grid DEM needs it for ~20% of its checks, where the
// separate pass was faster (H100, 2M grid points: flips 23 ms separate, 34 ms inlined; 2M uniform: 10.6
// vs 9.3).
constexpr uint32_t kInlineExactBelow = 1024;

// Block sums of each level of an exclusive scan of up to n elements (the primitives' scan allocates them per
// call; a build runs two scans a round). Each level starts on a 256-byte boundary, the largest storage-buffer
// offset alignment Vulkan allows.
constexpr uint64_t kLevelAlign = 256;
uint64_t align_up(uint64_t v) { return (v + kLevelAlign - 1) / kLevelAlign * kLevelAlign; }

// The round's copy of a bit set of `words` words kept twice (dt_rank clears the other one for the next
// round; dt_insert_small clears what it set, and the rounds it runs come first, after the fills).
Binding bit_set(const Buffer& b, uint64_t words, uint32_t round) {
  return Binding(b, (round & 1) * align_up(words * 4), words * 4);
}
uint64_t scan_scratch_bytes(uint64_t n) {
  uint64_t bytes = kLevelAlign;
  for (uint64_t m = n; m > 1; m = (m + SCAN_BLOCK - 1) / SCAN_BLOCK)
    bytes += align_up((m + SCAN_BLOCK - 1) / SCAN_BLOCK * 4);
  return bytes;
}

// A host-visible, coherent, persistently mapped buffer: the counters are copied into it at the end of every
// submit, so reading them costs no submit of its own.
Buffer create_readback(const Context& ctx, VkDeviceSize bytes, void** mapped) {
  Buffer b;
  b.device = ctx.device;
  b.size = bytes;
  b.name = "dt readback";
  VkBufferCreateInfo bi{};
  bi.sType = VK_STRUCTURE_TYPE_BUFFER_CREATE_INFO;
  bi.size = bytes;
  bi.usage = VK_BUFFER_USAGE_TRANSFER_DST_BIT;
  bi.sharingMode = VK_SHARING_MODE_EXCLUSIVE;
  VK_CHECK(vkCreateBuffer(ctx.device, &bi, nullptr, &b.buffer));
  VkMemoryRequirements req;
  vkGetBufferMemoryRequirements(ctx.device, b.buffer, &req);
  const VkMemoryPropertyFlags need =
      VK_MEMORY_PROPERTY_HOST_VISIBLE_BIT | VK_MEMORY_PROPERTY_HOST_COHERENT_BIT;
  VkMemoryAllocateInfo ai{};
  ai.sType = VK_STRUCTURE_TYPE_MEMORY_ALLOCATE_INFO;
  ai.allocationSize = req.size;
  ai.memoryTypeIndex = UINT32_MAX;
  for (uint32_t i = 0; i < ctx.memory.memoryTypeCount && ai.memoryTypeIndex == UINT32_MAX; ++i)
    if ((req.memoryTypeBits & (1u << i)) && (ctx.memory.memoryTypes[i].propertyFlags & need) == need)
      ai.memoryTypeIndex = i;
  if (ai.memoryTypeIndex == UINT32_MAX)
    throw DeviceError("no host-visible coherent memory on " + ctx.info.name);
  VK_CHECK(vkAllocateMemory(ctx.device, &ai, nullptr, &b.memory));
  VK_CHECK(vkBindBufferMemory(ctx.device, b.buffer, b.memory, 0));
  VK_CHECK(vkMapMemory(ctx.device, b.memory, 0, VK_WHOLE_SIZE, 0, mapped));
  return b;
}

}  // namespace

Buffer DelaunayBuilder::scratch(const char* key, uint64_t bytes, const char* name) const {
  return cache ? cache->take(ctx_, key, bytes, name) : create_buffer(ctx_, bytes, name);
}

// Everything one build holds on the device, and the host's view of the counters.
struct DelaunayBuilder::State {
  explicit State(const Context& ctx) : rec(ctx) {}

  GpuTriangulation tri;
  uint32_t n = 0;
  uint32_t first[3] = {0, 0, 0};  // the first triangle, counter-clockwise
  double corners[6] = {};         // its points' coordinates (walks outside the hull use their centroid)
  Buffer reduce;                  // dt_points results
  // The points in build numbering (Morton order, dt_renumber), and the canonical id of each; tri.points is
  // released while the build runs and rewritten at the end (dt_number_back).
  Buffer pts, perm;
  BufferCache* keep = nullptr;  // build(keep): where the slots and the numbering come from
  Buffer loc, list, loc2, list2;  // per list position: a point's slot code, its id; compaction targets
  Buffer pick, claim, partner, flip[2];
  Buffer bids;     // the slots with a bid this round
  // Two copies each, one per round parity (bit_set): a bit per slot (its split was granted this round), a bit
  // per list position (its point's split was granted); the ranks of the granted positions.
  Buffer granted, granted_at, ranks;
  Buffer counters, args, scan_sums;
  Buffer readback;
  void* host = nullptr;  // readback, mapped
  Buffer pass_log;       // profile_kernels: each flip pass's list length, in recording order
  void* pass_log_host = nullptr;
  uint32_t logged_passes = 0;
  uint32_t log_round = 0;     // the round the kernels being recorded belong to
  uint32_t log_list_len = 0;  // the point list's length in that round
  uint32_t list_len = 0;      // entries in `list` (some may have become vertices in the last round)
  uint32_t left = 0;          // points not yet vertices
  uint32_t used = 0;          // slots in use
  uint32_t round = 0;
  bool in_round = false;  // the submits belong to st.log_round (its time goes to stats->round_log)
  bool filled = false;    // pick, claim, counters and bit sets initialised (round 0, or the Voronoi start)
  uint32_t start_vertices = 3;
  bool sampling = false;  // only every sample_stride-th listed point walks and bids (the first rounds)
  uint32_t sampled_rounds = 0;
  uint32_t small_rounds = 0;
  uint32_t epoch = 0;              // of the last claim step (a round's splits, a flip pass); 0 is never used
  uint32_t cur = 0;                // the flip list the next pass reads
  uint32_t passes_last_round = 0;  // non-empty flip passes the last round needed: the next first batch
  uint32_t exact_last_round = 0;   // flip checks the last round decided exactly (ExactChecks::adaptive)
  uint32_t exact_before = 0;
  uint32_t flips_before = 0;
  std::array<uint32_t, DT_COUNTERS> c{};
  std::optional<Profiler> prof;
  DelaunayStats* stats = nullptr;
  // One command buffer, submitted once per round and per extra flip batch. Last, so that it goes first: an
  // unsubmitted recording ends before the buffers it names are destroyed.
  Recorder rec;

  bool detail = false;  // a stage per kernel as well (DelaunayBuilder::profile_kernels)

  // Free pick and claim words, clear bit sets: what the first round (or the Voronoi start's flips) expects.
  void fill_round_state() {
    rec.fill(pick, DT_NONE);
    rec.fill(claim, DT_NONE);
    rec.fill(granted, 0);
    rec.fill(granted_at, 0);
    filled = true;
  }

  // Flip passes so far that were dispatched (not run by a pass's last workgroup): what a batch must cover.
  uint32_t dispatched_passes() const { return c[DT_FLIP_PASSES] - c[DT_TAIL_DONE]; }

  void begin(const char* stage) {
    if (prof) prof->begin(rec, stage);
  }
  void end() {
    if (prof) prof->end(rec);
  }
  // Records one kernel (or scan) through `record`, timed on its own in detail mode.
  template <class F>
  void kernel(const char* name, F&& record) {
    if (detail) begin(name);
    record();
    if (detail) end();
  }
};

DelaunayBuilder::DelaunayBuilder(const Context& ctx)
    : exact_checks(ctx.info.type == "cpu" ? ExactChecks::separate : ExactChecks::adaptive),
      tail_passes(ctx.info.type != "cpu"),
      small_rounds(ctx.props.limits.maxComputeWorkGroupInvocations >= DT_SMALL_WG &&
                   ctx.props.limits.maxComputeWorkGroupSize[0] >= DT_SMALL_WG),
      ctx_(ctx),
      prims_(ctx),
      points_(create_pass(ctx, {"dt_points", 2, sizeof(DtPointsPush)})),
      init_(create_pass(ctx, {"dt_init", 6, sizeof(DtInitPush)})),
      renumber_(create_pass(ctx, {"dt_renumber", 6, sizeof(DtInitPush)})),
      hint_(create_pass(ctx, {"dt_hint", 1, sizeof(DtRoundPush)})),
      number_back_(create_pass(ctx, {"dt_number_back", 5, sizeof(DtRoundPush)})),
      flags_(create_pass(ctx, {"dt_flags", 2, sizeof(DtRoundPush)})),
      relocate_(create_pass(ctx, {"dt_relocate", 10, sizeof(DtRoundPush)})),
      relocate_exact_(create_pass(ctx, {"dt_relocate_exact", 10, sizeof(DtRoundPush)})),
      compact_(create_pass(ctx, {"dt_compact", 6, sizeof(DtRoundPush)})),
      claim_(create_pass(ctx, {"dt_claim", 6, sizeof(DtRoundPush)})),
      grant_(create_pass(ctx, {"dt_grant", 6, sizeof(DtRoundPush)})),
      rank_(create_pass(ctx, {"dt_rank", 5, sizeof(DtRoundPush)})),
      split_(create_pass(ctx, {"dt_split", 11, sizeof(DtRoundPush)})),
      split_fix_(create_pass(ctx, {"dt_split_fix", 13, sizeof(DtRoundPush)})),
      flip_check_(create_pass(ctx, {"dt_flip_check", 9, sizeof(DtFlipPush)})),
      flip_check_exact_(create_pass(ctx, {"dt_flip_check_exact", 8, sizeof(DtFlipPush)})),
      flip_(create_pass(ctx, {"dt_flip", 9, sizeof(DtFlipPush)})) {
  // The variants this device's defaults use, queued with the rest: a first run (empty pipeline caches) then
  // compiles them while the input is read, not in the middle of its first build. The others stay lazy (each
  // exact stage costs lavapipe seconds of compiling).
  if (small_rounds) insert_small();
  if (exact_checks != ExactChecks::separate) flip_check_inline();
  if (tail_passes) flip_tail();
}

const Pass& DelaunayBuilder::insert_small() const {
  if (!insert_small_) insert_small_.emplace(create_pass(ctx_, {"dt_insert_small", 12, sizeof(DtRoundPush)}));
  return *insert_small_;
}

const Pass& DelaunayBuilder::flip_check_inline() const {
  if (!flip_check_inline_)
    flip_check_inline_.emplace(create_pass(ctx_, {"dt_flip_check_inline", 9, sizeof(DtFlipPush)}));
  return *flip_check_inline_;
}

const Pass& DelaunayBuilder::flip_tail() const {
  if (!flip_tail_) flip_tail_.emplace(create_pass(ctx_, {"dt_flip_tail", 9, sizeof(DtFlipPush)}));
  return *flip_tail_;
}

GpuTriangulation DelaunayBuilder::build(std::span<const double> xy, DelaunayStats* stats) const {
  const uint32_t n = uint32_t(xy.size() / 2);
  return build(upload_new(ctx_, xy.subspan(0, size_t(n) * 2), "points"), n, stats);
}

GpuTriangulation DelaunayBuilder::build(Buffer points, uint32_t n, DelaunayStats* stats, BufferCache* keep) const {
  if (n > DT_MAX_SLOTS / 2)
    throw DeviceError("delaunay: " + std::to_string(n) + " points; at most " +
                      std::to_string(DT_MAX_SLOTS / 2));
  State st(ctx_);
  st.n = n;
  st.stats = stats;
  st.keep = keep;
  st.tri.points = std::move(points);
  st.tri.num_points = n;
  if (stats) {
    *stats = DelaunayStats{};
    st.detail = profile_kernels;
    st.prof.emplace(ctx_, profile_kernels ? 512 : 16);
    if (profile_kernels) st.pass_log = create_readback(ctx_, 4 * kPassLog, &st.pass_log_host);
  }
  if (n < 3 || !first_triangle(st)) {  // nothing to triangulate: no slots
    st.tri.verts = create_addressed_buffer(ctx_, 0, "tri_verts");
    st.tri.nbrs = create_addressed_buffer(ctx_, 0, "tri_nbrs");
    return std::move(st.tri);
  }
  start(st);
  if (initial_dt == Start::voronoi) voronoi_start(st);
  while (st.left > 0) {
    insert_round(st);
    flip_passes(st);
  }
  if (st.used != slot_capacity(n))
    throw DeviceError("delaunay: " + std::to_string(st.used) + " slots in use at the end, expected " +
                      std::to_string(slot_capacity(n)));
  st.tri.num_slots = st.used;
  release(st.loc, kPoints4[0]);  // the scratch goes back for the next stage (constraints) or build
  release(st.list, kPoints4[1]);
  release(st.list2, kPoints4[2]);
  release(st.loc2, kPoints4[3]);
  release(st.pick, kSlots8[0]);
  release(st.claim, kSlots8[1]);
  release(st.partner, kSlots4[0]);
  release(st.flip[0], kSlots4[1]);
  release(st.flip[1], kSlots4[2]);
  release(st.bids, kSlots4[3]);
  number_back(st);
  if (stats) {
    stats->rounds = st.round;
    stats->start_vertices = st.start_vertices;
    stats->flips = st.c[DT_FLIPS];
    stats->exact_walks = st.c[DT_EXACT_WALKS];
    stats->exact_checks = st.c[DT_EXACT_CHECKS];
    stats->flip_passes = st.c[DT_FLIP_PASSES];
    stats->tail_passes = st.c[DT_TAIL_DONE];
    stats->sampled_rounds = st.sampled_rounds;
    stats->small_rounds = st.small_rounds;
    stats->peak_device_bytes = peak_bytes(n) + stats->voronoi.device_bytes;  // vd buffers live beside the build's
  }
  return std::move(st.tri);
}

// v0 = point 0 (lexicographic minimum), v1 = point n-1 (maximum), v2 = the point farthest from the line v0-v1
// by a double estimate, checked exactly here; should the estimate pick a collinear point (all points on a
// line up to rounding), an exact scan on the host looks for any point off the line. None: all collinear, no
// triangles.
bool DelaunayBuilder::first_triangle(State& st) const {
  const uint32_t n = st.n;
  st.reduce = kept(st, kReduceKey, 4 * sizeof(uint64_t));
  st.readback = create_readback(ctx_, std::max<size_t>(DT_COUNTERS * 4, 64), &st.host);
  st.begin("start");
  st.rec.fill(st.reduce, 0xFFFFFFFFu);
  st.rec.dispatch_groups(points_, {st.tri.points, st.reduce}, DtPointsPush{n, 0, n - 1}, groups(n));
  st.rec.copy(st.reduce, st.readback, 3 * sizeof(uint64_t));
  st.end();
  submit(st, false);
  uint32_t c = uint32_t(static_cast<const uint64_t*>(st.host)[2]);
  for (uint32_t k = 0; k < 3; ++k)
    st.rec.copy(st.tri.points, st.readback, 16, uint64_t(k == 0 ? 0 : k == 1 ? n - 1 : c) * 16, k * 16);
  submit(st, false);
  pred::XY p[3];
  std::memcpy(p, st.host, sizeof(p));
  int o = pred::orient2d(p[0], p[1], p[2]);
  if (o == 0) {
    std::vector<double> xy = download_vector<double>(ctx_, st.tri.points, size_t(n) * 2);
    for (c = 1; c + 1 < n; ++c) {
      p[2] = {xy[2 * c], xy[2 * c + 1]};
      o = pred::orient2d(p[0], p[1], p[2]);
      if (o != 0) break;
    }
    if (o == 0) return false;
  }
  for (int k = 0; k < 3; ++k) {
    st.corners[2 * k] = p[k].x;
    st.corners[2 * k + 1] = p[k].y;
  }
  st.first[0] = 0;
  st.first[1] = o > 0 ? n - 1 : c;
  st.first[2] = o > 0 ? c : n - 1;
  return true;
}

uint64_t DelaunayBuilder::peak_bytes(uint32_t n) {
  if (n < 3) return uint64_t(n) * 16 + 64;
  const uint64_t slots = slot_capacity(n);
  const uint64_t result = uint64_t(n) * 16 + slots * 24;      // points (build numbering), verts, nbrs
  const uint64_t per_point = uint64_t(n) * 4 * 5;             // loc, list, loc2, list2, perm
  const uint64_t per_slot = slots * (8 + 8 + 4 + 4 + 4 + 4);  // pick, claim, partner, 2 flip lists, bids
  const uint64_t small = 32 + (DT_COUNTERS + DT_ARGS_WORDS) * 4 + std::max(DT_COUNTERS * 4, 64);
  const uint64_t bits = 2 * align_up(rank_words(slots) * 4) + 2 * align_up(rank_words(n) * 4) +
                        ranks_words(n) * 4;  // granted, granted_at (twice each), ranks
  return result + per_point + per_slot + scan_scratch_bytes(slots) + bits + small;
}

// Slots 0..3 (the first triangle and its three infinite neighbours); every other point is located in slot 0
// and numbered in Morton order (a key of 12 or 16 bits per axis over the bounding box), so that points with
// near numbers lie together: every coordinate read of the build is then local. The keys sit in flip list 0
// (idle until the first round). The canonical points are released (the build's copy replaces them until
// number_back), and the other per-slot arrays are allocated after the sort has released its scratch: a lower
// peak.
void DelaunayBuilder::start(State& st) const {
  const uint32_t n = st.n, slots = slot_capacity(n);
  st.tri.capacity = slots;
  auto slots_buffer = [&](const char* name) {
    return st.keep ? st.keep->take_addressed(ctx_, name, uint64_t(slots) * 12, name)
                   : create_addressed_buffer(ctx_, uint64_t(slots) * 12, name);
  };
  st.tri.verts = slots_buffer("tri_verts");
  st.tri.nbrs = slots_buffer("tri_nbrs");
  st.loc = scratch(kPoints4[0], uint64_t(n) * 4, "dt loc");
  st.list = scratch(kPoints4[1], uint64_t(n) * 4, "dt list");
  st.flip[0] = scratch(kSlots4[1], uint64_t(slots) * 4, "dt flip list 0");
  st.begin("start");
  // At most 4M points: 12 bits per axis (16M cells, 4 or more per point) order them as well, in three sort
  // passes instead of four.
  const uint32_t sort_bits = n <= (1u << 22) ? 24 : 32;
  const DtInitPush init{n, st.first[0], st.first[1], st.first[2], 32 - sort_bits};
  st.rec.dispatch_groups(init_, {st.tri.points, st.reduce, st.tri.verts, st.tri.nbrs, st.flip[0], st.list},
                         init, groups(n));
  // With a cache (tiles), the sort's scratch is the two point arrays the build takes next (list2, loc2): no
  // allocation per tile (~50 ms of device-held time for a 134M-point tile). Without, temporaries: a lower peak.
  Buffer sort_keys, sort_payload;
  if (cache) {
    sort_keys = scratch(kPoints4[2], uint64_t(n) * 4, "dt list2");
    sort_payload = scratch(kPoints4[3], uint64_t(n) * 4, "dt loc2");
  }
  prims_.radix_sort(st.rec, st.flip[0], st.list, n, 32, sort_bits,
                    cache ? SortScratch{&sort_keys, &sort_payload} : SortScratch{});
  // Not from the cache: kept there, they would add 20 B/pt to the later stages' peak (the constraint
  // inserter, the canonical sort).
  st.pts = kept(st, kPtsKey, uint64_t(n) * 16, "dt points (build numbering)");
  st.perm = kept(st, kPermKey, uint64_t(n) * 4, "dt canonical ids");
  st.rec.dispatch_groups(renumber_, {st.tri.points, st.list, st.loc, st.pts, st.perm, st.tri.verts}, init,
                         groups(n));
  st.end();
  submit(st, false);
  release(st.tri.points, kPoints16[0]);
  if (cache) release(sort_keys, kPoints4[2]), release(sort_payload, kPoints4[3]);
  st.list2 = scratch(kPoints4[2], uint64_t(n) * 4, "dt list2");
  st.loc2 = scratch(kPoints4[3], uint64_t(n) * 4, "dt loc2");
  st.pick = scratch(kSlots8[0], uint64_t(slots) * 8, "dt pick");
  st.claim = scratch(kSlots8[1], uint64_t(slots) * 8, "dt claim");
  st.partner = scratch(kSlots4[0], uint64_t(slots) * 4, "dt partner");
  st.flip[1] = scratch(kSlots4[2], uint64_t(slots) * 4, "dt flip list 1");
  st.bids = scratch(kSlots4[3], uint64_t(slots) * 4, "dt bid list");
  st.granted = kept(st, kGrantedKey, 2 * align_up(rank_words(slots) * 4));
  st.granted_at = kept(st, kGrantedAtKey, 2 * align_up(rank_words(n) * 4));
  st.ranks = kept(st, kRanksKey, ranks_words(n) * 4);
  st.counters = kept(st, kCountersKey, DT_COUNTERS * 4);
  st.args = kept(st, kArgsKey, DT_ARGS_WORDS * 4);
  st.scan_sums = kept(st, kScanSumsKey, scan_scratch_bytes(slots));
  st.list_len = n;
  st.left = n - 3;
  st.used = 4;
  st.sampling = sample_stride > 1 && n >= sample_min_points;
}

// The Voronoi first stage (gpu/voronoi_start) on the points start() numbered: the valid triangulation of the
// sites the digital dual kept replaces the first triangle's slots, every edge is checked and flipped until none
// is illegal (the walks need a Delaunay triangulation: in others they may cycle), and the rounds insert the
// points it lost, each from a slot near it. No valid start: the first triangle stays (a fallback, counted).
void DelaunayBuilder::voronoi_start(State& st) const {
  if (!voronoi_) voronoi_.emplace(ctx_);
  VoronoiStats local;
  VoronoiStats& vs = st.stats ? st.stats->voronoi : local;
  vs.used = true;
  std::optional<VoronoiStart> v = voronoi_->run(st.rec, st.pts, st.n, st.prof.has_value(), vs);
  const auto t0 = std::chrono::steady_clock::now();
  // The slots' upload below belongs to the host part too: added to "vd repair (host)" once it is done.
  auto add_stages = [&] {
    if (!st.stats) return;
    const double upload_ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
    for (auto& [name, ms] : vs.stage_ms) {
      if (name == "vd repair (host)") ms += upload_ms;
      st.stats->stage_ms.push_back({name, ms});
    }
  };
  if (!v) {
    add_stages();
    return;
  }
  const uint32_t slots = uint32_t(v->slots.verts.size() / 3);
  upload(ctx_, st.tri.verts, v->slots.verts.data(), v->slots.verts.size() * 4);
  upload(ctx_, st.tri.nbrs, v->slots.nbrs.data(), v->slots.nbrs.size() * 4);
  upload(ctx_, st.loc, v->loc.data(), v->loc.size() * 4);
  RawVector<uint32_t> list(slots);
  tbb::parallel_for(tbb::blocked_range<uint32_t>(0, slots, 1 << 14), [&](const tbb::blocked_range<uint32_t>& r) {
    for (uint32_t t = r.begin(); t < r.end(); ++t) list[t] = DT_ENTRY(t, DT_CHECK_ALL, 0u);
  });
  upload(ctx_, st.flip[0], list.data(), list.size() * 4);
  std::vector<uint32_t> counters(DT_COUNTERS, 0), args(DT_ARGS_WORDS, 0);
  counters[DT_COUNT_LIST0] = slots;
  counters[DT_FLIP_PASSES] = 1;  // the first pass's list, as dt_round_listed counts a round's
  for (uint32_t at = 0; at < DT_ARGS_WORDS; at += 3) args[at + 1] = args[at + 2] = 1;  // 0 groups
  const uint32_t g = uint32_t(groups(slots)), x = std::min(g, 65535u);
  args[DT_ARGS_LIST0] = x;
  args[DT_ARGS_LIST0 + 1] = (g + x - 1) / x;
  upload(ctx_, st.counters, counters.data(), counters.size() * 4);
  upload(ctx_, st.args, args.data(), args.size() * 4);
  st.fill_round_state();
  st.used = slots;
  st.start_vertices = v->slots.vertices;
  st.left = st.n - v->slots.vertices;
  st.list_len = st.n;
  st.sampling = false;  // the sample is for rounds over few slots
  std::copy(std::begin(v->corners), std::end(v->corners), st.corners);
  st.cur = 0;
  add_stages();
  const uint32_t passes_before = st.dispatched_passes();
  do {
    const uint32_t exact_before = st.c[DT_EXACT_CHECKS];
    record_flip_batch(st, flip_passes_per_submit, "vd flips");
    submit(st, true);
    st.exact_last_round = st.c[DT_EXACT_CHECKS] - exact_before;
  } while (st.c[DT_COUNT_LIST0 + st.cur] != 0);
  vs.flips = st.c[DT_FLIPS];
  vs.flip_passes = st.dispatched_passes() - passes_before;
}

// One round, one submit: every point left walks to its slot and bids for it (relocate; walks the filters
// cannot finish go to the exact pass); the list is compacted once a quarter of it are vertices; every slot
// with a bid inserts its winner where the claims allow (claim, grant, rank, split, fix); then the first batch
// of flip passes, as many as the last round needed and one more. Flip list 0 holds the walk flags and flip
// list 1 the scans: both lists are idle between rounds.
void DelaunayBuilder::insert_round(State& st) const {
  const uint32_t cap = slot_capacity(st.n);
  const Buffer &flags = st.flip[0], &offsets = st.flip[1];
  st.log_round = st.round;
  st.in_round = true;
  if (st.stats) st.stats->round_log.push_back({});

  st.begin("relocate");
  if (!st.filled) {  // recorded here, not in start(): a build of 3 points has no round and no submit
    st.rec.fill(st.counters, 0);
    st.fill_round_state();
  }
  // The sample runs low (fewer than sample_until of its points per slot in use are left; every point inserted
  // so far was a sample point): from now on every point walks, the others from a sample point's slot
  // (dt_hint).
  const uint64_t samples = (uint64_t(st.n) + sample_stride - 1) / sample_stride;
  if (st.sampling && samples < uint64_t(st.n - 3 - st.left) + uint64_t(sample_until) * st.used) {
    st.sampling = false;
    const DtRoundPush all{st.list_len, st.used, 0, cap, st.round, 0, sample_stride, {}};
    st.kernel("k:hint", [&] { st.rec.dispatch_groups(hint_, {st.loc}, all, groups(all.n)); });
  }
  // Compaction first, when a quarter of the list are vertices: the points still to insert keep their order,
  // their loc codes move with them, and the round's bids name positions in the compacted list. Not while
  // sampling: the sample is a set of positions.
  if (!st.sampling && uint64_t(st.list_len - st.left) * 4 >= st.list_len) {
    const DtRoundPush all{st.list_len, st.used, 0, cap, st.round, 0, 0, {}};
    st.kernel("k:compact", [&] {
      st.rec.dispatch_groups(flags_, {st.loc, flags}, all, groups(all.n));
      scan(st, flags, offsets, all.n);
      st.rec.dispatch_groups(compact_, {st.list, flags, offsets, st.list2, st.loc, st.loc2}, all,
                             groups(all.n));
    });
    std::swap(st.list, st.list2);
    std::swap(st.loc, st.loc2);
    st.list_len = st.left;
  }
  st.log_list_len = st.list_len;
  const uint32_t stride = st.sampling ? sample_stride : 1;
  st.sampled_rounds += st.sampling ? 1 : 0;
  DtRoundPush points{st.list_len, st.used, st.used + 16, cap, st.round, 0, stride, {}};
  std::copy(std::begin(st.corners), std::end(st.corners), points.corners);
  st.kernel("k:relocate", [&] {
    st.rec.dispatch_groups(relocate_,
                           {st.pts, st.tri.verts, st.tri.nbrs, st.loc, st.list, st.pick, st.list2,
                            st.counters, st.args, st.bids},
                           points, groups((uint64_t(points.n) + stride - 1) / stride));
  });
  st.kernel("k:relocate_exact", [&] {
    st.rec.dispatch_indirect(relocate_exact_,
                             {st.pts, st.tri.verts, st.tri.nbrs, st.loc, st.pick, st.list2, st.counters,
                              st.args, st.bids, st.list},
                             &points, st.args, DT_ARGS_RELOC * sizeof(uint32_t));
  });
  st.end();

  st.begin("insert");
  // Over the bid list (indirect, sized by dt_relocate_exact), not over every slot: late rounds have a few
  // thousand bids and millions of slots.
  const DtRoundPush slots{points.n, st.used, 0, cap, st.round, ++st.epoch, 0, {}};
  const VkDeviceSize bid_args = DT_ARGS_BIDS * sizeof(uint32_t);
  const uint32_t words = (points.n + 31) / 32;
  const uint64_t slot_words = rank_words(cap), point_words = rank_words(st.n);
  const uint32_t clear_slots = uint32_t(slot_words), clear_points = uint32_t(point_words);
  const DtRoundPush rank{words, st.used, clear_points, clear_slots, st.round, st.epoch, 0, {}};
  const Binding granted = bit_set(st.granted, slot_words, st.round);
  const Binding granted_at = bit_set(st.granted_at, point_words, st.round);
  if (small_rounds && st.used <= DT_SMALL_SLOTS) {
    ++st.small_rounds;
    st.kernel("k:insert_small", [&] {
      st.rec.dispatch_groups(insert_small(),
                             {st.tri.verts, st.tri.nbrs, st.loc, st.pick, st.claim, st.bids, st.counters,
                              st.args, granted, st.partner, st.flip[0], st.list},
                             slots, 1);
    });
  } else {
    st.kernel("k:claim", [&] {
      st.rec.dispatch_indirect(claim_, {st.tri.nbrs, st.loc, st.pick, st.claim, st.bids, st.counters}, &slots,
                               st.args, bid_args);
    });
    st.kernel("k:grant+rank", [&] {
      st.rec.dispatch_indirect(grant_, {st.pick, st.claim, granted, st.bids, st.counters, granted_at}, &slots,
                               st.args, bid_args);
      st.rec.dispatch_groups(
          rank_,
          {granted_at, st.ranks, st.counters, bit_set(st.granted, slot_words, st.round + 1),
           bit_set(st.granted_at, point_words, st.round + 1)},
          rank, groups(std::max<uint64_t>({words, slot_words, point_words})));
    });
    st.kernel("k:split", [&] {
      st.rec.dispatch_indirect(split_,
                               {st.tri.verts, st.tri.nbrs, st.loc, st.pick, granted, st.partner, st.counters,
                                st.ranks, st.bids, granted_at, st.list},
                               &slots, st.args, bid_args);
    });
    st.kernel("k:split_fix", [&] {
      st.rec.dispatch_indirect(split_fix_,
                               {st.tri.verts, st.tri.nbrs, st.loc, st.pick, granted, st.partner, st.claim,
                                st.counters, st.args, st.ranks, st.bids, granted_at, st.flip[0]},
                               &slots, st.args, bid_args);
    });
  }
  st.end();
  st.cur = 0;

  const uint32_t passes_before = st.dispatched_passes();
  st.exact_before = st.c[DT_EXACT_CHECKS];
  st.flips_before = st.c[DT_FLIPS];
  record_flip_batch(st, st.passes_last_round + 1);
  submit(st, true);
  ++st.round;
  const uint32_t winners = st.c[DT_WINNERS];
  if (winners == 0) throw DeviceError("delaunay: an insertion round inserted nothing");
  if (st.stats) st.stats->round_log.back().inserted = winners;
  st.left -= winners;
  st.used += 2 * winners;
  st.passes_last_round = st.dispatched_passes() - passes_before;
}

// Further batches of flip passes until the list is empty: the triangulation is then Delaunay again.
void DelaunayBuilder::flip_passes(State& st) const {
  while (st.c[DT_COUNT_LIST0 + st.cur] != 0) {
    const uint32_t passes_before = st.dispatched_passes();
    record_flip_batch(st, flip_passes_per_submit);
    submit(st, true);
    st.passes_last_round += st.dispatched_passes() - passes_before;
  }
  st.exact_last_round = st.c[DT_EXACT_CHECKS] - st.exact_before;
  if (st.stats) {
    st.stats->round_flip_passes.push_back(st.passes_last_round);
    st.stats->round_log.back().flips = st.c[DT_FLIPS] - st.flips_before;
  }
}

// `passes` flip passes, each: check (filters: requests and claims; the last workgroup sizes the exact pass),
// check the undecided slots exactly (or both in one kernel: ExactChecks), flip (winners flip and repair their
// neighbours; the next list; the last workgroup sizes the next pass). Indirect dispatches over the current
// list: no host round trip between passes.
void DelaunayBuilder::record_flip_batch(State& st, uint32_t passes, const char* stage) const {
  const uint32_t cap = slot_capacity(st.n);
  const bool inlined = exact_checks == ExactChecks::inlined ||
                       (exact_checks == ExactChecks::adaptive && st.exact_last_round < kInlineExactBelow);
  // The tail's checks are exact inline, in one workgroup: worth it only while few checks need the exact
  // stage.
  const bool tail = tail_passes && (inlined || exact_checks == ExactChecks::separate);
  const Pass& check = inlined ? flip_check_inline() : flip_check_;
  const Pass& flip = tail ? flip_tail() : flip_;
  st.begin(stage);
  for (uint32_t k = 0; k < passes; ++k) {
    const uint32_t src = st.cur;
    const DtFlipPush fp{src, cap, ++st.epoch};
    if (tail) st.epoch += DT_TAIL_PASSES;  // the epochs of the last workgroup's passes
    const VkDeviceSize at = (src == 0 ? DT_ARGS_LIST0 : DT_ARGS_LIST1) * sizeof(uint32_t);
    const Buffer& list = st.flip[src];
    if (st.detail && st.logged_passes < kPassLog)
      st.rec.copy(st.counters, st.pass_log, 4, (DT_COUNT_LIST0 + src) * 4, 4 * st.logged_passes++);
    st.kernel("k:flip_check", [&] {
      st.rec.dispatch_indirect(
          check,
          {st.pts, st.tri.verts, st.tri.nbrs, st.claim, st.partner, list, st.pick, st.counters, st.args}, &fp,
          st.args, at);
    });
    if (!inlined)
      st.kernel("k:flip_check_exact", [&] {
        st.rec.dispatch_indirect(
            flip_check_exact_,
            {st.pts, st.tri.verts, st.tri.nbrs, st.claim, st.partner, list, st.pick, st.counters}, &fp,
            st.args, DT_ARGS_FLIP * sizeof(uint32_t));
      });
    st.kernel("k:flip", [&] {
      st.rec.dispatch_indirect(flip,
                               {st.tri.verts, st.tri.nbrs, st.claim, st.partner, st.flip[0], st.flip[1],
                                st.counters, st.args, st.pts},
                               &fp, st.args, at);
    });
    st.cur = 1 - src;
  }
  st.end();
}

// The slots' corners back to canonical ids and the coordinates to canonical order, into a fresh points
// buffer (the canonical one was released at the start); the build's copies are freed.
void DelaunayBuilder::number_back(State& st) const {
  const uint32_t n = st.n;
  st.tri.points = scratch(kPoints16[0], uint64_t(n) * 16, "points");
  st.tri.vertex_slots = scratch(kPoints4[0], uint64_t(n) * 4, "vertex slots");  // the build's loc, just given back
  st.in_round = false;
  st.begin("number back");
  const DtRoundPush push{n, st.used, 0, 0, 0, 0, 0, {}};
  st.rec.dispatch_groups(number_back_, {st.pts, st.perm, st.tri.verts, st.tri.points, st.tri.vertex_slots}, push,
                         groups(std::max<uint64_t>(n, uint64_t(st.used) * 3)));
  st.end();
  submit(st, false);
  // The build's own buffers, small ones too: a tile allocated and freed them all (the device's allocations
  // serialise between devices: 14 s of 34 at 1B points on two).
  if (st.keep)
    for (auto& [key, b] : {std::pair<const char*, Buffer*>{kPtsKey, &st.pts}, {kPermKey, &st.perm},
                           {kGrantedKey, &st.granted}, {kGrantedAtKey, &st.granted_at}, {kRanksKey, &st.ranks},
                           {kCountersKey, &st.counters}, {kArgsKey, &st.args}, {kScanSumsKey, &st.scan_sums},
                           {kReduceKey, &st.reduce}})
      if (b->buffer) st.keep->give(key, std::move(*b));
  st.pts = Buffer{};
  st.perm = Buffer{};
}

// A buffer of the build's own from the caller's cache (tiles: kept from one tile to the next), or made.
Buffer DelaunayBuilder::kept(State& st, const char* key, uint64_t bytes, const char* name) const {
  if (!name) name = key;
  return st.keep ? st.keep->take(ctx_, key, bytes, name) : create_buffer(ctx_, bytes, name);
}

// A scratch buffer back to the cache under `key`, or freed.
void DelaunayBuilder::release(Buffer& b, const char* key) const {
  if (cache)
    cache->give(key, std::move(b));
  else
    b = Buffer{};
}

// Exclusive scan with the build's own block sums (the primitives' passes, levels as in Primitives).
void DelaunayBuilder::scan(State& st, const Buffer& in, const Buffer& out, uint32_t n) const {
  struct Level {
    uint32_t n, blocks;
    VkDeviceSize at;
  };
  std::vector<Level> levels;
  VkDeviceSize at = 0;
  for (uint32_t m = n; m > 1;) {
    const uint32_t blocks = (m + SCAN_BLOCK - 1) / SCAN_BLOCK;
    levels.push_back({m, blocks, at});
    at += align_up(uint64_t(blocks) * 4);
    m = blocks;
  }
  if (n == 1) levels.push_back({1, 1, 0});
  for (size_t l = 0; l < levels.size(); ++l) {
    const Level& v = levels[l];
    const Binding src = l == 0 ? Binding(in) : Binding(st.scan_sums, levels[l - 1].at, uint64_t(v.n) * 4);
    const Binding dst = l == 0 ? Binding(out) : src;
    const Binding sums(st.scan_sums, v.at, uint64_t(v.blocks) * 4);
    st.rec.dispatch_groups(prims_.scan_block, {src, dst, sums}, ScanPush{v.n, v.blocks > 1 ? 1u : 0u, 0u},
                           v.blocks);
    if (v.blocks == 1) break;
  }
  for (size_t l = levels.size(); l-- > 0;) {
    const Level& v = levels[l];
    if (v.blocks == 1) continue;
    const Binding dst = l == 0 ? Binding(out) : Binding(st.scan_sums, levels[l - 1].at, uint64_t(v.n) * 4);
    st.rec.dispatch_groups(prims_.scan_add, {dst, Binding(st.scan_sums, v.at, uint64_t(v.blocks) * 4)},
                           ScanAddPush{v.n}, v.blocks);
  }
}

// Submits the recording and waits; `counters`: copy the counters into the readback buffer first, then check
// them. The stage times go to the stats.
void DelaunayBuilder::submit(State& st, bool counters) const {
  if (counters) st.rec.copy(st.counters, st.readback, DT_COUNTERS * sizeof(uint32_t));
  st.rec.submit();
  if (st.prof) {
    const auto* lengths = static_cast<const uint32_t*>(st.pass_log_host);
    uint32_t pass = 0;
    for (const StageTime& s : st.prof->results()) {
      if (st.in_round && s.name.rfind("k:", 0) != 0) st.stats->round_log.back().ms += s.ms;
      if (st.detail && s.name.rfind("k:", 0) == 0) {
        const bool check = s.name == "k:flip_check";
        const uint32_t items = check && pass < st.logged_passes ? lengths[pass]
                               : s.name == "k:relocate"         ? st.log_list_len
                                                                : 0u;
        st.stats->kernel_log.push_back({st.log_round, s.name, s.ms, items});
        pass += check ? 1 : 0;
      }
      auto& stages = st.stats->stage_ms;
      auto it = std::find_if(stages.begin(), stages.end(), [&](const auto& e) { return e.first == s.name; });
      if (it == stages.end())
        stages.push_back({s.name, s.ms});
      else
        it->second += s.ms;
    }
    st.prof->reset();
    st.logged_passes = 0;
  }
  if (!counters) return;
  std::memcpy(st.c.data(), st.host, DT_COUNTERS * sizeof(uint32_t));
  const std::pair<int, const char*> errors[] = {{DT_NONCONVEX, "illegal edges with a non-convex quad"},
                                                {DT_WALK_FAIL, "relocation walks past the step cap"},
                                                {DT_OVERFLOW, "list overflows"},
                                                {DT_BEYOND, "hull apexes between the ends of a hull edge"}};
  for (auto [at, what] : errors)
    if (st.c[at]) throw DeviceError("delaunay: " + std::to_string(st.c[at]) + " " + what + " (a bug)");
}

GpuTriangulation build_delaunay(const Context& ctx, std::span<const double> xy, DelaunayStats* stats) {
  return DelaunayBuilder(ctx).build(xy, stats);
}

std::vector<std::pair<std::string, double>> bench_delaunay(const DelaunayBuilder& dt,
                                                           std::span<const double> xy, int runs) {
  const Context& ctx = dt.context();
  const uint32_t n = uint32_t(xy.size() / 2);
  std::map<std::string, std::vector<double>> samples;
  std::vector<std::string> order;
  auto add = [&](const std::string& name, double ms) {
    if (!samples.count(name)) order.push_back(name);
    samples[name].push_back(ms);
  };
  for (int r = 0; r < std::max(runs, 1); ++r) {
    Buffer points = upload_new(ctx, xy.subspan(0, size_t(n) * 2), "points");
    DelaunayStats stats;
    auto t0 = std::chrono::steady_clock::now();
    GpuTriangulation tri = dt.build(std::move(points), n, &stats);
    auto t1 = std::chrono::steady_clock::now();
    double total = 0;
    for (auto& [name, ms] : stats.stage_ms) {
      add(name, ms);
      total += ms;
    }
    add("gpu_total", total);
    add("wall", std::chrono::duration<double, std::milli>(t1 - t0).count());
  }
  std::vector<std::pair<std::string, double>> out;
  for (const std::string& name : order) {
    std::vector<double>& v = samples[name];
    std::sort(v.begin(), v.end());
    out.push_back({name, v[v.size() / 2]});
  }
  return out;
}

}  // namespace cdtgpu::gpu
