float16 __attribute__((overloadable)) vload16(size_t o, const private float* p) { float16 r; __builtin_memcpy(&r, p + 16 * o, 64); return r; }
int16 __attribute__((overloadable)) vload16(size_t o, const private int* p) { int16 r; __builtin_memcpy(&r, p + 16 * o, 64); return r; }
void __attribute__((overloadable)) vstore16(float16 v, size_t o, private float* p) { __builtin_memcpy(p + 16 * o, &v, 64); }
void __attribute__((overloadable)) vstore16(int16 v, size_t o, private int* p) { __builtin_memcpy(p + 16 * o, &v, 64); }
uint __attribute__((overloadable)) atomic_add(volatile global uint* p, uint v) { uint o = *p; *p = o + v; return o; }
float8 __attribute__((overloadable)) vload8(size_t o, const global float* p) { float8 r; __builtin_memcpy(&r, p + 8 * o, 32); return r; }
float4 __attribute__((overloadable)) vload4(size_t o, const global float* p) { float4 r; __builtin_memcpy(&r, p + 4 * o, 16); return r; }
