// The TIN rasterised to a DEM grid on the GPU: core/raster.hpp's rules and values, bit for bit.
//
//   gpu::GpuRasteriser raster(ctx, prims);                  // builds its three pipelines
//   gpu::DeviceTin tin = gpu::upload_tin(ctx, mesh);         // gpu/tin.hpp
//   Raster dem = raster.rasterise(tin, grid_for(mesh, 1.0)); // == rasterise(mesh, 1.0), every double
//
// The grid is made in bands of whole rows, each band's doubles one storage buffer (at most
// maxStorageBufferRange: 16M cells on lavapipe, 512M on the H100; a 10000 x 10000 grid is one band there).
// Per band: raster_spans (a thread per triangle: its rows and columns in the band), a scan, raster_claim (a
// thread per (triangle, row): atomicMin of the triangle index into each centre it holds, so the smallest
// index wins as on the CPU; orientation filters only, the centres they cannot decide are queued),
// raster_exact (a thread per queued centre: exact orient2d, then the same atomicMin), raster_values (a thread
// per cell: the winner's interpolation, `precise`, divisions correctly rounded), then the band is downloaded
// into its rows of the Raster.
// Cost: O(triangles) per band plus the centres of the bounding boxes, like the CPU.
#pragma once
#include <cstdint>

#include "core/raster.hpp"
#include "gpu/passes.hpp"
#include "gpu/primitives.hpp"
#include "gpu/tin.hpp"

namespace cdtgpu::gpu {

class GpuRasteriser {
 public:
  GpuRasteriser(const Context& ctx, const Primitives& prims);
  // max_band_cells: cells per band at most (0: as many as the device's buffer range holds); tests make it
  // small to check that bands join seamlessly. Throws DeviceError when one grid row alone exceeds the range.
  Raster rasterise(const DeviceTin& tin, const GridSpec& spec, uint64_t max_band_cells = 0) const;
  // Milliseconds of the last call on the device (timestamps, all bands).
  mutable double gpu_ms = 0;

 private:
  const Context& ctx_;
  const Primitives& prims_;
  Pass spans_, claim_, exact_, values_;
};

}  // namespace cdtgpu::gpu
