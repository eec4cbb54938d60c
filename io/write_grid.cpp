// ESRI ASCII grid writer (GDAL's AAIGrid; QGIS, ArcGIS and cdtgpu's own read_ascii_grid read it). The header
// uses xllcenter / yllcenter so the cell centres, multiples of the cell size, are written exactly. Rows are
// formatted on all cores in blocks and written in order as they come (a TBB pipeline), so the text is the
// same as one thread writing it, and formatting overlaps the writing.
#include <tbb/parallel_pipeline.h>
#include <tbb/task_arena.h>

#include <algorithm>
#include <cctype>
#include <filesystem>
#include <memory>

#include "io/atomic_file.hpp"
#include "io/geotiff.hpp"
#include "io/gis_writers.hpp"
#include "io/text_out.hpp"

namespace cdtgpu {

namespace {

// About this many cells a block: large enough that a block outweighs its hand-over, small enough that the
// blocks in flight (a few per core) stay within tens of MiB.
constexpr uint64_t kBlockCells = 1 << 16;

struct Block {
  uint64_t row0 = 0, rows = 0;
  std::unique_ptr<char[]> text;
  size_t size = 0;
};

}  // namespace

void write_ascii_grid(const Raster& raster, std::ostream& out) {
  const GridSpec& g = raster.spec;
  {
    TextOut o(out);
    o.text("ncols ").number(g.ncols).text("\nnrows ").number(g.nrows);
    o.text("\nxllcenter ").number(g.x(0)).text("\nyllcenter ").number(g.y(g.nrows - 1));
    o.text("\ncellsize ").number(g.cell).text("\nNODATA_value ").number(Raster::nodata).ch('\n');
    o.flush();
  }
  const uint64_t block_rows = std::max<uint64_t>(1, kBlockCells / std::max<uint64_t>(1, g.ncols));
  uint64_t next = 0;
  tbb::parallel_pipeline(
      size_t(4 * tbb::this_task_arena::max_concurrency()),
      tbb::make_filter<void, Block*>(tbb::filter_mode::serial_in_order, [&](tbb::flow_control& fc) -> Block* {
        if (next >= g.nrows) {
          fc.stop();
          return nullptr;
        }
        auto* b = new Block{next, std::min(block_rows, g.nrows - next), {}, 0};
        next += b->rows;
        return b;
      }) & tbb::make_filter<Block*, Block*>(tbb::filter_mode::parallel, [&](Block* b) {
        // Each value, a space or line end after it.
        b->text.reset(new char[b->rows * g.ncols * (TextOut::kMaxNumberChars + 1)]);
        char* p = b->text.get();
        for (uint64_t row = b->row0; row < b->row0 + b->rows; ++row) {
          const double* z = raster.z.data() + row * g.ncols;
          for (uint64_t col = 0; col < g.ncols; ++col) {
            if (col) *p++ = ' ';
            p = TextOut::put_number(p, z[col]);
          }
          *p++ = '\n';
        }
        b->size = size_t(p - b->text.get());
        return b;
      }) & tbb::make_filter<Block*, void>(tbb::filter_mode::serial_in_order, [&](Block* b) {
        std::unique_ptr<Block> own(b);
        if (out) out.write(b->text.get(), std::streamsize(b->size));
      }));
  if (!out) throw std::runtime_error("write failed");
}

void write_ascii_grid_file(const Raster& raster, const Crs& crs, const std::string& path) {
  write_file_atomically(path, [&](std::ostream& out) { write_ascii_grid(raster, out); });
  write_prj_beside(path, crs);
}

void write_grid_file(const Raster& raster, const Crs& crs, const std::string& path) {
  std::string ext = std::filesystem::path(path).extension().string();
  for (char& c : ext) c = char(std::tolower(static_cast<unsigned char>(c)));
  if (ext == ".tif" || ext == ".tiff")
    write_geotiff_grid_file(raster, crs, path);
  else
    write_ascii_grid_file(raster, crs, path);
}

void write_prj_beside(const std::string& path, const Crs& crs) {
  if (path == "-" || crs.wkt.empty()) return;
  const std::string prj = std::filesystem::path(path).replace_extension(".prj").string();
  write_file_atomically(prj, [&](std::ostream& out) { out << crs.wkt; });
}

}  // namespace cdtgpu
