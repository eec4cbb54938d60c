// Appends to a list whose length is one counter word, or adds to such a word, with one atomic per subgroup
// instead of one per invocation: atomics on one address queue (on the H100 ~0.4 ns each, so 4M of them take
// 1.7 ms). The active invocations that reach the macro share it, so it may sit in divergent code. The including
// shader enables GL_KHR_shader_subgroup_basic, _arithmetic and _ballot.
#ifndef CDTGPU_SUBGROUP_APPEND_GLSL
#define CDTGPU_SUBGROUP_APPEND_GLSL

// at = this invocation's entry in the list counted by `counter` (a buffer word).
#define SUBGROUP_APPEND(at, counter)                    \
  {                                                      \
    uint sa_total = subgroupAdd(1u), sa_base = 0u;       \
    if (subgroupElect()) sa_base = atomicAdd(counter, sa_total); \
    at = subgroupBroadcastFirst(sa_base) + subgroupExclusiveAdd(1u); \
  }

// counter += v of every active invocation.
#define SUBGROUP_ADD(counter, v)                     \
  {                                                  \
    uint sa_sum = subgroupAdd(v);                    \
    if (subgroupElect() && sa_sum != 0u) atomicAdd(counter, sa_sum); \
  }

#endif
