// Helpers every compute shader may include: the linear workgroup index of a dispatch split over x and y.
#ifndef CDTGPU_COMMON_GLSL
#define CDTGPU_COMMON_GLSL

uint linear_group_id() { return gl_WorkGroupID.y * gl_NumWorkGroups.x + gl_WorkGroupID.x; }

#endif
