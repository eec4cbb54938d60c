// The triangulation's per-slot words (verts, nbrs: three per slot) are reached through buffer device addresses:
// at 12 bytes per slot they pass maxStorageBufferRange (4 GiB on NVIDIA) near 180M points, and an address has
// no range. The binding holds the buffer's address (gpu/recorder.cpp writes it); a shader declares
//   layout(std430, binding = N) restrict readonly buffer VertsAt { TriWordsR verts_at; };
//   #define verts(i) TRI_WORD(TriWordsR, verts_at, i)
// and reads or writes word i as verts(i). The qualifier of the words goes with the type: TriWords, TriWordsR
// (readonly), TriWordsW (writeonly), TriWordsC (coherent). The address of word i is computed in 64 bits: an
// index into a reference's array is 32-bit, and the H100's driver wraps index * 4 at 4 GiB (185M points gave
// wrong neighbours where the slots passed it).
#ifndef CDTGPU_TRI_REFS_GLSL
#define CDTGPU_TRI_REFS_GLSL
#extension GL_EXT_buffer_reference : require
#extension GL_EXT_shader_explicit_arithmetic_types_int64 : require

layout(buffer_reference, std430, buffer_reference_align = 4) buffer TriWords { uint v[]; };
layout(buffer_reference, std430, buffer_reference_align = 4) readonly buffer TriWordsR { uint v[]; };
layout(buffer_reference, std430, buffer_reference_align = 4) writeonly buffer TriWordsW { uint v[]; };
layout(buffer_reference, std430, buffer_reference_align = 4) coherent buffer TriWordsC { uint v[]; };

#define TRI_WORD(T, ref, i) T(uint64_t(ref) + 4ul * uint64_t(i)).v[0]

#endif
