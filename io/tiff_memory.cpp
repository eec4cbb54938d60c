// libtiff's client I/O over memory. Reading maps the caller's bytes (libtiff then reads strips and tiles
// straight from them); writing grows a string. Messages come through libtiff 4.5's per-handle handlers.
#include "io/tiff_memory.hpp"

#include <xtiffio.h>

#include <algorithm>
#include <cstdarg>
#include <cstdio>
#include <cstring>
#include <mutex>
#include <stdexcept>

#include "core/error.hpp"
#include "io/geotiff_lib.hpp"

namespace cdtgpu::tiff {

struct Handle::State {
  std::string_view in;  // reading
  std::string out;      // writing
  bool writing = false;
  uint64_t pos = 0;
  std::string message;
  uint64_t size() const { return writing ? out.size() : in.size(); }
};

namespace {

using State = Handle::State;

tmsize_t read_proc(thandle_t h, void* buf, tmsize_t n) {
  auto* s = static_cast<State*>(h);
  const std::string_view data = s->writing ? std::string_view(s->out) : s->in;
  if (n < 0 || s->pos >= data.size()) return 0;
  const size_t k = std::min<uint64_t>(uint64_t(n), data.size() - s->pos);
  std::memcpy(buf, data.data() + s->pos, k);
  s->pos += k;
  return tmsize_t(k);
}

tmsize_t write_proc(thandle_t h, void* buf, tmsize_t n) {
  auto* s = static_cast<State*>(h);
  if (!s->writing || n < 0) return -1;
  if (s->pos + uint64_t(n) > s->out.size()) s->out.resize(s->pos + uint64_t(n));
  std::memcpy(s->out.data() + s->pos, buf, size_t(n));
  s->pos += uint64_t(n);
  return n;
}

toff_t seek_proc(thandle_t h, toff_t off, int whence) {
  auto* s = static_cast<State*>(h);
  uint64_t base = whence == SEEK_CUR ? s->pos : whence == SEEK_END ? s->size() : 0;
  s->pos = base + off;
  return s->pos;
}

int close_proc(thandle_t) { return 0; }
toff_t size_proc(thandle_t h) { return static_cast<State*>(h)->size(); }

int map_proc(thandle_t h, void** base, toff_t* size) {
  auto* s = static_cast<State*>(h);
  if (s->writing) return 0;
  *base = const_cast<char*>(s->in.data());
  *size = s->in.size();
  return 1;
}
void unmap_proc(thandle_t, void*, toff_t) {}

std::string format(const char* fmt, va_list ap) {
  char buf[512];
  std::vsnprintf(buf, sizeof buf, fmt, ap);
  return buf;
}

int on_error(TIFF*, void* user, const char* module, const char* fmt, va_list ap) {
  auto* s = static_cast<State*>(user);
  s->message = format(fmt, ap);
  if (module && *module) s->message = std::string(module) + ": " + s->message;
  return 1;
}

int on_warning(TIFF*, void*, const char*, const char*, va_list) { return 1; }

TIFFExtendProc g_next_extender = nullptr;

// GDAL's NODATA tag as GDAL declares it (ASCII, no count); libtiff would otherwise read it as an anonymous
// tag with a count.
void add_gdal_fields(TIFF* tif) {
  static const TIFFFieldInfo info[] = {
      {TIFFTAG_GDAL_NODATA, -1, -1, TIFF_ASCII, FIELD_CUSTOM, 1, 0, const_cast<char*>("GDALNoDataValue")}};
  TIFFMergeFieldInfo(tif, info, 1);
  if (g_next_extender) g_next_extender(tif);
}

// Once per process: libgeotiff's tags and GDAL_NODATA known to libtiff, and libtiff's process-wide handlers
// (still used by a few of its calls that have no handle) quiet.
void init() {
  static std::once_flag once;
  std::call_once(once, [] {
    geotiff_lib().initialize();
    g_next_extender = TIFFSetTagExtender(add_gdal_fields);
    TIFFSetErrorHandler(nullptr);
    TIFFSetWarningHandler(nullptr);
  });
}

TIFF* open(const char* name, const char* mode, State* s, uint64_t max_alloc) {
  init();
  TIFFOpenOptions* opts = TIFFOpenOptionsAlloc();
  TIFFOpenOptionsSetErrorHandlerExtR(opts, on_error, s);
  TIFFOpenOptionsSetWarningHandlerExtR(opts, on_warning, s);
  if (max_alloc) TIFFOpenOptionsSetMaxSingleMemAlloc(opts, tmsize_t(max_alloc));
  TIFF* tif = TIFFClientOpenExt(name, mode, s, read_proc, write_proc, seek_proc, close_proc, size_proc,
                                map_proc, unmap_proc, opts);
  TIFFOpenOptionsFree(opts);
  return tif;
}

void geotiff_message(GTIF* gt, int level, const char* fmt, ...) {
  if (level != LIBGEOTIFF_ERROR) return;
  auto* s = static_cast<State*>(geotiff_lib().user_data(gt));
  va_list ap;
  va_start(ap, fmt);
  s->message = "GeoKeys: " + format(fmt, ap);
  va_end(ap);
}

}  // namespace

Handle::Handle() = default;
Handle::Handle(Handle&& o) noexcept : tif_(o.tif_), state_(std::move(o.state_)) { o.tif_ = nullptr; }
Handle& Handle::operator=(Handle&& o) noexcept {
  std::swap(tif_, o.tif_);
  std::swap(state_, o.state_);
  return *this;
}
Handle::~Handle() {
  if (tif_) TIFFClose(tif_);
}

const std::string& Handle::message() const { return state_->message; }

std::string Handle::finish() {
  TIFF* t = tif_;
  tif_ = nullptr;
  // TIFFClose writes the directory; it reports a failure only through the error handler.
  state_->message.clear();
  TIFFClose(t);
  if (!state_->message.empty()) throw std::runtime_error("TIFF: " + state_->message);
  return std::move(state_->out);
}

Handle open_read(std::string_view bytes, const std::string& name, uint64_t max_alloc) {
  Handle h;
  h.state_ = std::make_unique<State>();
  h.state_->in = bytes;
  // "rO": strip and tile offsets read on demand, so a handle per thread costs little even for many strips.
  h.tif_ = open(name.c_str(), "rO", h.state_.get(), max_alloc);
  if (!h.tif_)
    throw InputError(name, 0,
                     "not a TIFF file libtiff can read" +
                         (h.state_->message.empty() ? std::string() : ": " + h.state_->message));
  return h;
}

Handle open_write(bool bigtiff) {
  Handle h;
  h.state_ = std::make_unique<State>();
  h.state_->writing = true;
  h.tif_ = open("grid.tif", bigtiff ? "w8" : "w", h.state_.get(), 0);
  if (!h.tif_) throw std::runtime_error("libtiff cannot start a TIFF: " + h.state_->message);
  return h;
}

GTIF* geokeys(Handle& h) { return geotiff_lib().new_ex(h.tif_, geotiff_message, h.state_.get()); }

}  // namespace cdtgpu::tiff
