#include <cstdio>
int main() { std::puts("cdtgpu"); return 0; }
