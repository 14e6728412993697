/* The neurons' standard normals: Box-Muller in float32 on the counter-based word
 * mix64(key ^ step_hash(step)) of each channel (skinhil/model/rng.py states the definition).
 *
 * Three paths give bit-identical results: AVX-512 (16 lanes), AVX2 + FMA (8 lanes) and
 * portable C. Every float operation is the same IEEE operation in the same order on every
 * path: conversions of 32-bit words to float are correctly rounded (AVX2 builds them from
 * exact 16-bit halves), log, sin and cos are this file's own polynomials, every multiply-add
 * is a fused one (fmaf in portable C, which is exact), and the file is compiled with
 * -ffp-contract=off so the compiler fuses nothing else. The path is chosen when the library
 * is loaded (skinhil_normals_use), by the CPU or forced.
 */
#define PY_SSIZE_T_CLEAN
#include <Python.h>
#include <math.h>
#include <stdint.h>
#include <string.h>

#if (defined(__x86_64__) || defined(_M_X64)) && (defined(__GNUC__) || defined(__clang__))
#define SKINHIL_X86 1
#include <immintrin.h>
#endif

#define GAMMA 0x9E3779B97F4A7C15ULL
#define M1 0xBF58476D1CE4E5B9ULL
#define M2 0x94D049BB133111EBULL

/* log: m in [sqrt(1/2), sqrt(2)), ln(1 + f) = f - f^2/2 + f^3 P(f) (Cephes logf) */
#define LP0 7.0376836292e-2f
#define LP1 -1.1514610310e-1f
#define LP2 1.1676998740e-1f
#define LP3 -1.2420140846e-1f
#define LP4 1.4249322787e-1f
#define LP5 -1.6668057665e-1f
#define LP6 2.0000714765e-1f
#define LP7 -2.4999993993e-1f
#define LP8 3.3333331174e-1f
#define LN2_HI 0.693359375f
#define LN2_LO -2.12194440e-4f
#define SQRT_HALF_BITS 0x3f3504f3u /* bits of float(sqrt(0.5)) */
/* sin, cos on [0, pi/2): Taylor series to x^13 and x^12 */
#define S1 -1.66666666666666667e-1f
#define S2 8.33333333333333333e-3f
#define S3 -1.98412698412698413e-4f
#define S4 2.75573192239858907e-6f
#define S5 -2.50521083854417188e-8f
#define S6 1.60590438368216146e-10f
#define C1 -0.5f
#define C2 4.16666666666666667e-2f
#define C3 -1.38888888888888889e-3f
#define C4 2.48015873015873016e-5f
#define C5 -2.75573192239858907e-7f
#define C6 2.08767569878680990e-9f
#define HALF_PI 1.57079632679489662f
#define TWO_M32 2.3283064365386963e-10f /* 2^-32 */
#define TWO_M23 1.1920928955078125e-7f  /* 2^-23 */

static inline uint64_t mix64(uint64_t z) {
    z = (z ^ (z >> 30)) * M1;
    z = (z ^ (z >> 27)) * M2;
    return z ^ (z >> 31);
}

static uint64_t step_hash(int64_t step) { return mix64((uint64_t)(step + 1) * GAMMA); }

static inline float bits_float(uint32_t b) { float f; memcpy(&f, &b, 4); return f; }
static inline uint32_t float_bits(float f) { uint32_t b; memcpy(&b, &f, 4); return b; }

/* ---------------------------------------------------------------- portable C */

static inline void pair_scalar(uint64_t w, float *z1, float *z2) {
    uint32_t lo = (uint32_t)w, hi = (uint32_t)(w >> 32);
    /* radius: u = (lo + 1/2) 2^-32 in float32, t = -2 ln u */
    float u = ((float)lo + 0.5f) * TWO_M32;
    uint32_t ub = float_bits(u);
    uint32_t mb = (ub & 0x007fffffu) | 0x3f800000u;    /* mantissa in [1, 2) */
    int32_t e = (int32_t)(ub >> 23) - 127;
    if (mb > 0x3fb504f3u) { mb -= 0x00800000u; e += 1; } /* m > sqrt 2: m / 2 */
    float f = bits_float(mb) - 1.0f;
    float fe = (float)e;
    float z = f * f;
    float p = LP0;
    p = fmaf(p, f, LP1); p = fmaf(p, f, LP2); p = fmaf(p, f, LP3); p = fmaf(p, f, LP4);
    p = fmaf(p, f, LP5); p = fmaf(p, f, LP6); p = fmaf(p, f, LP7); p = fmaf(p, f, LP8);
    float y = (p * f) * z;
    y = fmaf(fe, LN2_LO, y);
    y = fmaf(z, -0.5f, y);
    float ln = fmaf(fe, LN2_HI, f + y);
    float t = fmaxf(-2.0f * ln, 0.0f);
    float r = sqrtf(t);
    /* angle: quadrant from the top 2 bits of hi, x = (a + 1/2) 2^-23 pi/2 from the next 23 */
    uint32_t q = hi >> 30;
    float x = (((float)((hi >> 7) & 0x007fffffu) + 0.5f) * TWO_M23) * HALF_PI;
    float x2 = x * x;
    float ps = S6;
    ps = fmaf(ps, x2, S5); ps = fmaf(ps, x2, S4); ps = fmaf(ps, x2, S3);
    ps = fmaf(ps, x2, S2); ps = fmaf(ps, x2, S1);
    float s = fmaf(x * x2, ps, x);
    float pc = C6;
    pc = fmaf(pc, x2, C5); pc = fmaf(pc, x2, C4); pc = fmaf(pc, x2, C3);
    pc = fmaf(pc, x2, C2); pc = fmaf(pc, x2, C1);
    float c = fmaf(x2, pc, 1.0f);
    uint32_t cb = float_bits(c), sb = float_bits(s);
    uint32_t cx = (q & 1u) ? (sb ^ 0x80000000u) : cb;  /* q odd: (cos, sin) -> (-sin, cos) */
    uint32_t sx = (q & 1u) ? cb : sb;
    uint32_t neg = (q & 2u) ? 0x80000000u : 0u;        /* q >= 2: both negated */
    *z1 = r * bits_float(cx ^ neg);
    *z2 = r * bits_float(sx ^ neg);
}

static void normals_portable(const uint64_t *keys, int64_t n, int64_t step, float *z1,
                             float *z2) {
    uint64_t h = step_hash(step);
    for (int64_t i = 0; i < n; i++) pair_scalar(mix64(keys[i] ^ h), &z1[i], &z2[i]);
}

#ifdef SKINHIL_X86
/* ---------------------------------------------------------------- AVX2 + FMA, 8 lanes */
#define T_AVX2 __attribute__((target("avx2,fma")))

T_AVX2 static inline __m256i mul64_avx2(__m256i a, __m256i b) {
    /* the low 64 bits of a·b per lane: lo·lo + ((hi·lo + lo·hi) << 32) */
    __m256i ll = _mm256_mul_epu32(a, b);
    __m256i hl = _mm256_mul_epu32(_mm256_srli_epi64(a, 32), b);
    __m256i lh = _mm256_mul_epu32(a, _mm256_srli_epi64(b, 32));
    return _mm256_add_epi64(ll, _mm256_slli_epi64(_mm256_add_epi64(hl, lh), 32));
}

T_AVX2 static inline __m256i mix64_avx2(__m256i z) {
    z = mul64_avx2(_mm256_xor_si256(z, _mm256_srli_epi64(z, 30)),
                   _mm256_set1_epi64x((long long)M1));
    z = mul64_avx2(_mm256_xor_si256(z, _mm256_srli_epi64(z, 27)),
                   _mm256_set1_epi64x((long long)M2));
    return _mm256_xor_si256(z, _mm256_srli_epi64(z, 31));
}

T_AVX2 static inline __m256 u32_to_float_avx2(__m256i x) {
    /* correctly rounded: the high and low 16 bits exactly, one rounding in the add */
    __m256 hi = _mm256_mul_ps(_mm256_cvtepi32_ps(_mm256_srli_epi32(x, 16)),
                              _mm256_set1_ps(65536.0f));
    __m256 lo = _mm256_cvtepi32_ps(_mm256_and_si256(x, _mm256_set1_epi32(0xffff)));
    return _mm256_add_ps(hi, lo);
}

T_AVX2 static inline void pair_avx2(__m256i lo, __m256i hi, __m256 *z1, __m256 *z2) {
    __m256 u = _mm256_mul_ps(_mm256_add_ps(u32_to_float_avx2(lo), _mm256_set1_ps(0.5f)),
                             _mm256_set1_ps(TWO_M32));
    __m256i ub = _mm256_castps_si256(u);
    __m256i mb = _mm256_or_si256(_mm256_and_si256(ub, _mm256_set1_epi32(0x007fffff)),
                                 _mm256_set1_epi32(0x3f800000));
    __m256i e = _mm256_sub_epi32(_mm256_srli_epi32(ub, 23), _mm256_set1_epi32(127));
    __m256i big = _mm256_cmpgt_epi32(mb, _mm256_set1_epi32(0x3fb504f3));
    mb = _mm256_sub_epi32(mb, _mm256_and_si256(big, _mm256_set1_epi32(0x00800000)));
    e = _mm256_sub_epi32(e, big); /* big is -1 where m > sqrt 2 */
    __m256 f = _mm256_sub_ps(_mm256_castsi256_ps(mb), _mm256_set1_ps(1.0f));
    __m256 fe = _mm256_cvtepi32_ps(e);
    __m256 z = _mm256_mul_ps(f, f);
    __m256 p = _mm256_set1_ps(LP0);
    p = _mm256_fmadd_ps(p, f, _mm256_set1_ps(LP1));
    p = _mm256_fmadd_ps(p, f, _mm256_set1_ps(LP2));
    p = _mm256_fmadd_ps(p, f, _mm256_set1_ps(LP3));
    p = _mm256_fmadd_ps(p, f, _mm256_set1_ps(LP4));
    p = _mm256_fmadd_ps(p, f, _mm256_set1_ps(LP5));
    p = _mm256_fmadd_ps(p, f, _mm256_set1_ps(LP6));
    p = _mm256_fmadd_ps(p, f, _mm256_set1_ps(LP7));
    p = _mm256_fmadd_ps(p, f, _mm256_set1_ps(LP8));
    __m256 y = _mm256_mul_ps(_mm256_mul_ps(p, f), z);
    y = _mm256_fmadd_ps(fe, _mm256_set1_ps(LN2_LO), y);
    y = _mm256_fmadd_ps(z, _mm256_set1_ps(-0.5f), y);
    __m256 ln = _mm256_fmadd_ps(fe, _mm256_set1_ps(LN2_HI), _mm256_add_ps(f, y));
    __m256 t = _mm256_max_ps(_mm256_mul_ps(_mm256_set1_ps(-2.0f), ln), _mm256_setzero_ps());
    __m256 r = _mm256_sqrt_ps(t);
    __m256i q = _mm256_srli_epi32(hi, 30);
    __m256i a = _mm256_and_si256(_mm256_srli_epi32(hi, 7), _mm256_set1_epi32(0x007fffff));
    __m256 x = _mm256_mul_ps(_mm256_mul_ps(_mm256_add_ps(_mm256_cvtepi32_ps(a),
                                                         _mm256_set1_ps(0.5f)),
                                           _mm256_set1_ps(TWO_M23)),
                             _mm256_set1_ps(HALF_PI));
    __m256 x2 = _mm256_mul_ps(x, x);
    __m256 ps = _mm256_set1_ps(S6);
    ps = _mm256_fmadd_ps(ps, x2, _mm256_set1_ps(S5));
    ps = _mm256_fmadd_ps(ps, x2, _mm256_set1_ps(S4));
    ps = _mm256_fmadd_ps(ps, x2, _mm256_set1_ps(S3));
    ps = _mm256_fmadd_ps(ps, x2, _mm256_set1_ps(S2));
    ps = _mm256_fmadd_ps(ps, x2, _mm256_set1_ps(S1));
    __m256 s = _mm256_fmadd_ps(_mm256_mul_ps(x, x2), ps, x);
    __m256 pc = _mm256_set1_ps(C6);
    pc = _mm256_fmadd_ps(pc, x2, _mm256_set1_ps(C5));
    pc = _mm256_fmadd_ps(pc, x2, _mm256_set1_ps(C4));
    pc = _mm256_fmadd_ps(pc, x2, _mm256_set1_ps(C3));
    pc = _mm256_fmadd_ps(pc, x2, _mm256_set1_ps(C2));
    pc = _mm256_fmadd_ps(pc, x2, _mm256_set1_ps(C1));
    __m256 c = _mm256_fmadd_ps(x2, pc, _mm256_set1_ps(1.0f));
    __m256i sign = _mm256_set1_epi32((int)0x80000000u);
    __m256i odd = _mm256_cmpeq_epi32(_mm256_and_si256(q, _mm256_set1_epi32(1)),
                                     _mm256_set1_epi32(1));
    __m256i cb = _mm256_castps_si256(c), sb = _mm256_castps_si256(s);
    __m256i cx = _mm256_blendv_epi8(cb, _mm256_xor_si256(sb, sign), odd);
    __m256i sx = _mm256_blendv_epi8(sb, cb, odd);
    __m256i neg = _mm256_and_si256(_mm256_slli_epi32(_mm256_srli_epi32(q, 1), 31), sign);
    *z1 = _mm256_mul_ps(r, _mm256_castsi256_ps(_mm256_xor_si256(cx, neg)));
    *z2 = _mm256_mul_ps(r, _mm256_castsi256_ps(_mm256_xor_si256(sx, neg)));
}

T_AVX2 static void normals_avx2(const uint64_t *keys, int64_t n, int64_t step, float *z1,
                                float *z2) {
    uint64_t h = step_hash(step);
    __m256i hv = _mm256_set1_epi64x((long long)h);
    __m256i halves = _mm256_setr_epi32(0, 2, 4, 6, 1, 3, 5, 7);
    int64_t i = 0;
    for (; i + 8 <= n; i += 8) {
        __m256i wa = mix64_avx2(_mm256_xor_si256(
            _mm256_loadu_si256((const __m256i *)(keys + i)), hv));
        __m256i wb = mix64_avx2(_mm256_xor_si256(
            _mm256_loadu_si256((const __m256i *)(keys + i + 4)), hv));
        /* per word: low halves into the low 128 bits, high halves into the high 128 */
        __m256i pa = _mm256_permutevar8x32_epi32(wa, halves);
        __m256i pb = _mm256_permutevar8x32_epi32(wb, halves);
        __m256 a1, a2;
        pair_avx2(_mm256_permute2x128_si256(pa, pb, 0x20),
                  _mm256_permute2x128_si256(pa, pb, 0x31), &a1, &a2);
        _mm256_storeu_ps(z1 + i, a1);
        _mm256_storeu_ps(z2 + i, a2);
    }
    for (; i < n; i++) pair_scalar(mix64(keys[i] ^ h), &z1[i], &z2[i]);
}

/* ---------------------------------------------------------------- AVX-512, 16 lanes */
#define T_AVX512 __attribute__((target("avx512f,avx512dq,avx512bw,avx512vl")))

T_AVX512 static inline __m512i mix64_avx512(__m512i z) {
    z = _mm512_mullo_epi64(_mm512_xor_si512(z, _mm512_srli_epi64(z, 30)),
                           _mm512_set1_epi64((long long)M1));
    z = _mm512_mullo_epi64(_mm512_xor_si512(z, _mm512_srli_epi64(z, 27)),
                           _mm512_set1_epi64((long long)M2));
    return _mm512_xor_si512(z, _mm512_srli_epi64(z, 31));
}

T_AVX512 static inline void pair_avx512(__m512i lo, __m512i hi, __m512 *z1, __m512 *z2) {
    __m512 u = _mm512_mul_ps(_mm512_add_ps(_mm512_cvtepu32_ps(lo), _mm512_set1_ps(0.5f)),
                             _mm512_set1_ps(TWO_M32));
    __m512i ub = _mm512_castps_si512(u);
    __m512i mb = _mm512_or_si512(_mm512_and_si512(ub, _mm512_set1_epi32(0x007fffff)),
                                 _mm512_set1_epi32(0x3f800000));
    __m512i e = _mm512_sub_epi32(_mm512_srli_epi32(ub, 23), _mm512_set1_epi32(127));
    __mmask16 big = _mm512_cmpgt_epi32_mask(mb, _mm512_set1_epi32(0x3fb504f3));
    mb = _mm512_mask_sub_epi32(mb, big, mb, _mm512_set1_epi32(0x00800000));
    e = _mm512_mask_add_epi32(e, big, e, _mm512_set1_epi32(1));
    __m512 f = _mm512_sub_ps(_mm512_castsi512_ps(mb), _mm512_set1_ps(1.0f));
    __m512 fe = _mm512_cvtepi32_ps(e);
    __m512 z = _mm512_mul_ps(f, f);
    __m512 p = _mm512_set1_ps(LP0);
    p = _mm512_fmadd_ps(p, f, _mm512_set1_ps(LP1));
    p = _mm512_fmadd_ps(p, f, _mm512_set1_ps(LP2));
    p = _mm512_fmadd_ps(p, f, _mm512_set1_ps(LP3));
    p = _mm512_fmadd_ps(p, f, _mm512_set1_ps(LP4));
    p = _mm512_fmadd_ps(p, f, _mm512_set1_ps(LP5));
    p = _mm512_fmadd_ps(p, f, _mm512_set1_ps(LP6));
    p = _mm512_fmadd_ps(p, f, _mm512_set1_ps(LP7));
    p = _mm512_fmadd_ps(p, f, _mm512_set1_ps(LP8));
    __m512 y = _mm512_mul_ps(_mm512_mul_ps(p, f), z);
    y = _mm512_fmadd_ps(fe, _mm512_set1_ps(LN2_LO), y);
    y = _mm512_fmadd_ps(z, _mm512_set1_ps(-0.5f), y);
    __m512 ln = _mm512_fmadd_ps(fe, _mm512_set1_ps(LN2_HI), _mm512_add_ps(f, y));
    __m512 t = _mm512_max_ps(_mm512_mul_ps(_mm512_set1_ps(-2.0f), ln), _mm512_setzero_ps());
    __m512 r = _mm512_sqrt_ps(t);
    __m512i q = _mm512_srli_epi32(hi, 30);
    __m512i a = _mm512_and_si512(_mm512_srli_epi32(hi, 7), _mm512_set1_epi32(0x007fffff));
    __m512 x = _mm512_mul_ps(_mm512_mul_ps(_mm512_add_ps(_mm512_cvtepi32_ps(a),
                                                         _mm512_set1_ps(0.5f)),
                                           _mm512_set1_ps(TWO_M23)),
                             _mm512_set1_ps(HALF_PI));
    __m512 x2 = _mm512_mul_ps(x, x);
    __m512 ps = _mm512_set1_ps(S6);
    ps = _mm512_fmadd_ps(ps, x2, _mm512_set1_ps(S5));
    ps = _mm512_fmadd_ps(ps, x2, _mm512_set1_ps(S4));
    ps = _mm512_fmadd_ps(ps, x2, _mm512_set1_ps(S3));
    ps = _mm512_fmadd_ps(ps, x2, _mm512_set1_ps(S2));
    ps = _mm512_fmadd_ps(ps, x2, _mm512_set1_ps(S1));
    __m512 s = _mm512_fmadd_ps(_mm512_mul_ps(x, x2), ps, x);
    __m512 pc = _mm512_set1_ps(C6);
    pc = _mm512_fmadd_ps(pc, x2, _mm512_set1_ps(C5));
    pc = _mm512_fmadd_ps(pc, x2, _mm512_set1_ps(C4));
    pc = _mm512_fmadd_ps(pc, x2, _mm512_set1_ps(C3));
    pc = _mm512_fmadd_ps(pc, x2, _mm512_set1_ps(C2));
    pc = _mm512_fmadd_ps(pc, x2, _mm512_set1_ps(C1));
    __m512 c = _mm512_fmadd_ps(x2, pc, _mm512_set1_ps(1.0f));
    __m512i sign = _mm512_set1_epi32((int)0x80000000u);
    __mmask16 odd = _mm512_test_epi32_mask(q, _mm512_set1_epi32(1));
    __m512i cb = _mm512_castps_si512(c), sb = _mm512_castps_si512(s);
    __m512i cx = _mm512_mask_blend_epi32(odd, cb, _mm512_xor_si512(sb, sign));
    __m512i sx = _mm512_mask_blend_epi32(odd, sb, cb);
    __m512i neg = _mm512_slli_epi32(_mm512_srli_epi32(q, 1), 31);
    *z1 = _mm512_mul_ps(r, _mm512_castsi512_ps(_mm512_xor_si512(cx, neg)));
    *z2 = _mm512_mul_ps(r, _mm512_castsi512_ps(_mm512_xor_si512(sx, neg)));
}

T_AVX512 static void normals_avx512(const uint64_t *keys, int64_t n, int64_t step, float *z1,
                                    float *z2) {
    uint64_t h = step_hash(step);
    __m512i hv = _mm512_set1_epi64((long long)h);
    int64_t i = 0;
    for (; i + 16 <= n; i += 16) {
        __m512i wa = mix64_avx512(_mm512_xor_si512(_mm512_loadu_si512(keys + i), hv));
        __m512i wb = mix64_avx512(_mm512_xor_si512(_mm512_loadu_si512(keys + i + 8), hv));
        __m512i lo = _mm512_inserti64x4(_mm512_castsi256_si512(_mm512_cvtepi64_epi32(wa)),
                                        _mm512_cvtepi64_epi32(wb), 1);
        __m512i hi = _mm512_inserti64x4(
            _mm512_castsi256_si512(_mm512_cvtepi64_epi32(_mm512_srli_epi64(wa, 32))),
            _mm512_cvtepi64_epi32(_mm512_srli_epi64(wb, 32)), 1);
        __m512 a1, a2;
        pair_avx512(lo, hi, &a1, &a2);
        _mm512_storeu_ps(z1 + i, a1);
        _mm512_storeu_ps(z2 + i, a2);
    }
    for (; i < n; i++) pair_scalar(mix64(keys[i] ^ h), &z1[i], &z2[i]);
}
#endif /* SKINHIL_X86 */

/* ---------------------------------------------------------------- dispatch */

typedef void (*normals_fn)(const uint64_t *, int64_t, int64_t, float *, float *);
static normals_fn chosen = normals_portable;

/* 0 portable, 1 AVX2, 2 AVX-512: whether this CPU runs the path */
int skinhil_normals_supported(int path) {
    if (path == 0) return 1;
#ifdef SKINHIL_X86
    __builtin_cpu_init();
    if (path == 1) return __builtin_cpu_supports("avx2") && __builtin_cpu_supports("fma");
    if (path == 2)
        return __builtin_cpu_supports("avx512f") && __builtin_cpu_supports("avx512dq") &&
               __builtin_cpu_supports("avx512bw") && __builtin_cpu_supports("avx512vl");
#endif
    return 0;
}

/* use path (0, 1, 2), or the widest this CPU runs for -1; the path used, -1 if unsupported */
int skinhil_normals_use(int path) {
    if (path < 0) path = skinhil_normals_supported(2) ? 2 : skinhil_normals_supported(1) ? 1 : 0;
    if (!skinhil_normals_supported(path)) return -1;
#ifdef SKINHIL_X86
    chosen = path == 2 ? normals_avx512 : path == 1 ? normals_avx2 : normals_portable;
#else
    chosen = normals_portable;
#endif
    return path;
}

/* z1[i], z2[i]: the pair of standard normals of the channel with keys[i] at step */
void skinhil_normals(const uint64_t *keys, int64_t n, int64_t step, float *z1, float *z2) {
    chosen(keys, n, step, z1, z2);
}

/* A module with no functions: Python imports it to find this library, which ctypes opens. */
static struct PyModuleDef module = {PyModuleDef_HEAD_INIT, "_kernel", NULL, -1, NULL};

PyMODINIT_FUNC PyInit__kernel(void) { return PyModule_Create(&module); }
