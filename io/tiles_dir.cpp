#include "io/tiles_dir.hpp"

#include <fcntl.h>
#include <sys/file.h>
#include <unistd.h>

#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <stdexcept>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>

#include "core/canonical.hpp"
#include "core/error.hpp"
#include "io/atomic_file.hpp"

namespace cdtgpu {
namespace fs = std::filesystem;

namespace {

std::string tile_name(size_t t, const WriteOptions& options) {
  char name[32];
  std::snprintf(name, sizeof name, "tile_%04zu%s", t + 1, mesh_extension(options.format));
  return name;
}

// Test hook (tests/mpi_test): this process's tile files fail to write, as a full disk would make them.
void fail_for_tests(int rank) {
  if (const char* r = std::getenv("CDTGPU_MPI_TEST_FAIL_TILE_WRITE"); r && std::atoi(r) == rank)
    throw std::runtime_error("write failed (CDTGPU_MPI_TEST_FAIL_TILE_WRITE)");
}

// The lock on a run's own folder of new tiles, until it is renamed into place: a killed run's, which nobody
// locks, the next run removes (remove_killed_runs_temps). A file system that takes no lock on a folder, such as
// NFS, leaves both unlocked: nothing is removed there.
struct FolderHeld {
  int fd;
  explicit FolderHeld(const fs::path& p) : fd(::open(p.c_str(), O_RDONLY | O_DIRECTORY | O_CLOEXEC)) {
    if (fd >= 0) (void)::flock(fd, LOCK_EX | LOCK_NB);
  }
  ~FolderHeld() {
    if (fd >= 0) ::close(fd);
  }
};

}  // namespace

std::string tiles_dir_path(const std::string& dir) {
  const fs::path target = fs::path(dir).lexically_normal();
  return (target.filename().empty() ? target.parent_path() : target).string();
}

void write_tiles_dir(const std::vector<MeshPiece>& pieces, const Crs& crs, const WriteOptions& options,
                     const std::string& dir, const TilesDirSharing* sharing) {
  const fs::path clean = tiles_dir_path(dir);
  std::error_code ec;
  if (fs::exists(clean, ec) && !fs::is_directory(clean, ec))
    throw UsageError("--tiles-out " + dir + ": exists and is not a folder");
  const fs::path fresh = clean.string() + ".tmp-" + std::to_string(::getpid());
  remove_killed_runs_temps(clean.string(), fresh.string(), true, "the tiles");
  fs::remove_all(fresh, ec);
  fs::create_directories(fresh);
  const FolderHeld held(fresh);
  try {
    const int ranks = sharing ? sharing->ranks : 1;
    if (sharing)
      for (int r = 1; r < ranks; ++r) {
        std::vector<std::pair<size_t, const MeshPiece*>> theirs;
        for (size_t t = size_t(r); t < pieces.size(); t += size_t(ranks)) theirs.emplace_back(t, &pieces[t]);
        sharing->send(r, fresh.string(), crs, theirs);
      }
    std::string mine;
    try {
      if (sharing) fail_for_tests(0);
      for (size_t t = 0; t < pieces.size(); t += size_t(ranks))
        write_mesh_file(pieces[t].mesh, crs, options, (fresh / tile_name(t, options)).string());
    } catch (const std::exception& e) {
      if (!sharing) throw;
      mine = e.what();
    }
    if (sharing)
      for (const std::string& why : sharing->outcomes(mine))
        if (!why.empty()) throw std::runtime_error("--tiles-out " + dir + ": " + why);
    nlohmann::json features = nlohmann::json::array();
    for (size_t t = 0; t < pieces.size(); ++t) {
      const MeshPiece& p = pieces[t];
      features.push_back(
          {{"type", "Feature"},
           {"geometry",
            {{"type", "Polygon"},
             {"coordinates", {{{p.x0, p.y0}, {p.x1, p.y0}, {p.x1, p.y1}, {p.x0, p.y1}, {p.x0, p.y0}}}}}},
           {"properties",
            {{"tile", t + 1},
             {"file", tile_name(t, options)},
             {"vertices", p.mesh.vertices.size()},
             {"triangles", p.mesh.triangles.size()}}}});
    }
    nlohmann::json index{{"type", "FeatureCollection"}, {"features", features}};
    if (!crs.name.empty()) index["crs_name"] = crs.name;
    if (crs.epsg) index["crs_epsg"] = crs.epsg;
    write_file_atomically((fresh / "index.geojson").string(),
                          [&](std::ostream& out) { out << index.dump(1) << '\n'; });
    const fs::path old = clean.string() + ".old-" + std::to_string(::getpid());
    if (fs::exists(clean, ec)) fs::rename(clean, old);
    fs::rename(fresh, clean);
    fs::remove_all(old, ec);
    // A run killed between its renames or before the last removal left its previous tiles as DIR.old-<pid>,
    // which nobody locks; ours replace them now (had this run failed, they would stay: maybe the only copy).
    remove_killed_runs_temps(clean.string(), old.string(), true, "the tiles it replaced", ".old-");
  } catch (...) {
    fs::remove_all(fresh, ec);
    throw;
  }
}

void write_shared_tiles(const WriteOptions& options, const TilesDirSharing& sharing) {
  auto [fresh, crs, pieces] = sharing.receive();
  std::string mine;
  try {
    fail_for_tests(sharing.rank);
    for (const auto& [t, piece] : pieces)
      write_mesh_file(piece.mesh, crs, options, (fs::path(fresh) / tile_name(t, options)).string());
  } catch (const std::exception& e) {
    mine = e.what();
  }
  sharing.outcomes(mine);
}

Mesh read_tiles_dir(const std::string& dir) {
  const fs::path index_path = fs::path(dir) / "index.geojson";
  std::ifstream in(index_path);
  if (!in) throw InputError(index_path.string(), 0, "cannot open the tile index");
  nlohmann::json index;
  try {
    index = nlohmann::json::parse(in);
  } catch (const nlohmann::json::exception& e) {
    throw InputError(index_path.string(), 0, std::string("not JSON: ") + e.what());
  }
  if (!index.contains("features") || !index["features"].is_array())
    throw InputError(index_path.string(), 0, "no \"features\" array");
  Mesh all;
  uint64_t feature = 0;
  for (const auto& f : index["features"]) {
    ++feature;
    const auto& props = f.value("properties", nlohmann::json::object());
    if (!props.contains("file") || !props["file"].is_string())
      throw InputError(index_path.string(), feature, "feature without a \"file\" property");
    const std::string file = (fs::path(dir) / props["file"].get<std::string>()).string();
    const Mesh piece = read_mesh_file(file);
    if (props.value("vertices", uint64_t(0)) != piece.vertices.size() ||
        props.value("triangles", uint64_t(0)) != piece.triangles.size())
      throw InputError(file, 0, "holds other counts of vertices or triangles than the index says");
    const uint32_t base = uint32_t(all.vertices.size());
    all.vertices.insert(all.vertices.end(), piece.vertices.begin(), piece.vertices.end());
    for (const Triangle& t : piece.triangles)
      all.triangles.push_back({t[0] + base, t[1] + base, t[2] + base});
  }
  // Merge the repeated vertices: sorted by (x, y), the first of each run kept.
  std::vector<uint32_t> order(all.vertices.size());
  for (uint32_t i = 0; i < order.size(); ++i) order[i] = i;
  const auto& v = all.vertices;
  std::stable_sort(order.begin(), order.end(), [&](uint32_t a, uint32_t b) {
    return v[a].x != v[b].x ? v[a].x < v[b].x : v[a].y < v[b].y;
  });
  std::vector<uint32_t> merged(v.size());
  Points unique;
  for (size_t k = 0; k < order.size(); ++k) {
    const Point3& p = v[order[k]];
    if (unique.empty() || unique.back().x != p.x || unique.back().y != p.y) {
      unique.push_back(p);
    } else if (unique.back().z != p.z) {
      throw InputError(dir, 0, "a vertex shared by two tile files has two z values");
    }
    merged[order[k]] = uint32_t(unique.size() - 1);
  }
  for (Triangle& t : all.triangles)
    for (uint32_t& id : t) id = merged[id];
  all.vertices = std::move(unique);
  canonicalize(all);
  for (size_t i = 1; i < all.triangles.size(); ++i)
    if (all.triangles[i] == all.triangles[i - 1]) throw InputError(dir, 0, "a triangle is in two tile files");
  return all;
}

}  // namespace cdtgpu
