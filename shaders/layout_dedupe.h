// Push constants of the duplicate-merging passes (gpu/dedupe.cpp), shared by C++ and GLSL.
#ifndef CDTGPU_SHADERS_LAYOUT_DEDUPE_H
#define CDTGPU_SHADERS_LAYOUT_DEDUPE_H
#include "layout.h"

#ifdef __cplusplus
namespace cdtgpu::gpu::layout {
#endif

#define DEDUPE_WG 256

struct DedupeKeysPush {
  uint n;
  uint coord;   // 0: key of x, 1: key of y
  uint gather;  // 0: element i is point i (and idx[i] = i is written); 1: element i is point idx[i]
};

struct DedupePush {
  uint n;
};

#ifdef __cplusplus
}  // namespace cdtgpu::gpu::layout
#endif

#endif
