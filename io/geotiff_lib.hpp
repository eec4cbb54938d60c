// libgeotiff, loaded (dlopen) when a TIFF is first read or written. Linked, it brought PROJ and PROJ's ~40
// libraries (curl, gnutls, sqlite, kerberos ...) into every process: 9 of the 12 ms that `cdtgpu --version`
// took, paid by every run and every job of a script, most of which never see a GeoTIFF.
//
//   const tiff::GeoTiffLib& g = tiff::geotiff_lib();   // throws std::runtime_error naming what is missing
//   GTIF* gt = g.new_ex(tif, on_message, user);  ...  g.free(gt);
#pragma once
#include <geotiff.h>
#include <xtiffio.h>

namespace cdtgpu::tiff {

// The functions of libgeotiff that cdtgpu calls, by their names there.
struct GeoTiffLib {
  decltype(&::XTIFFInitialize) initialize = nullptr;  // its tags known to libtiff
  decltype(&::GTIFNewEx) new_ex = nullptr;
  decltype(&::GTIFFree) free = nullptr;
  decltype(&::GTIFGetUserData) user_data = nullptr;
  decltype(&::GTIFKeyGetSHORT) key_get_short = nullptr;
  decltype(&::GTIFKeySet) key_set = nullptr;
  decltype(&::GTIFWriteKeys) write_keys = nullptr;
};

// Loaded once per process (later calls return the same); throws std::runtime_error when the library or one of
// its functions is missing ("GeoTIFF needs libgeotiff (libgeotiff.so.5): ...").
const GeoTiffLib& geotiff_lib();

}  // namespace cdtgpu::tiff
