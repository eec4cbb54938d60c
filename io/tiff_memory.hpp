// libtiff handles over bytes in memory (a mapped file, a buffer being written), each keeping libtiff's and
// libgeotiff's messages for itself, so that threads decoding one file each with a handle of their own report
// their own errors and nothing is printed behind the caller's back.
//
//   tiff::Handle h = tiff::open_read(bytes, "dem.tif");    // throws InputError with libtiff's message
//   TIFFReadEncodedStrip(h.tif(), 3, buf, -1);             // on failure: h.message() says why
//   tiff::Handle w = tiff::open_write(false);              // classic TIFF ("w"); true: BigTIFF ("w8")
//   ... TIFFSetField / TIFFWriteRawTile ...;  std::string file = w.finish();
#pragma once
#include <geotiff.h>
#include <tiffio.h>

#include <cstdint>
#include <memory>
#include <string>
#include <string_view>

namespace cdtgpu::tiff {

class Handle {
 public:
  struct State;  // the bytes, the position and the messages (tiff_memory.cpp)
  Handle();
  Handle(Handle&&) noexcept;
  Handle& operator=(Handle&&) noexcept;
  ~Handle();
  TIFF* tif() const { return tif_; }
  // libtiff's (or libgeotiff's) last error since the handle was opened, "" when none.
  const std::string& message() const;
  // Writing: closes the TIFF (libtiff writes its directory then) and hands back the file's bytes.
  std::string finish();

 private:
  friend Handle open_read(std::string_view, const std::string&, uint64_t);
  friend Handle open_write(bool);
  friend GTIF* geokeys(Handle&);
  TIFF* tif_ = nullptr;
  std::unique_ptr<State> state_;
};

// Opens the first image of a TIFF held in `bytes` (which must outlive the handle), with the GeoTIFF tags
// known (libgeotiff's tag extender). `max_alloc`: the largest single allocation libtiff may make (0: its
// default). Throws InputError naming `name` when libtiff refuses the file.
Handle open_read(std::string_view bytes, const std::string& name, uint64_t max_alloc = 0);
// A TIFF written into memory. Throws std::runtime_error when libtiff cannot start one.
Handle open_write(bool bigtiff);

// libgeotiff's view of the handle's GeoKeys (GTIFFree it); its messages go to the handle's message(). Null
// when libgeotiff fails.
GTIF* geokeys(Handle& h);

}  // namespace cdtgpu::tiff
