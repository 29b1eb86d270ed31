/* The samplers behind sampler.h (zsobol's per-request draws are inline there, its blocks here). Stratified and Sobol' are "padded" (Kollig & Keller
 * 2002; Burley 2020 §4; pbrt-v4's PaddedSobolSampler): each 1D or 2D request is a
 * low-dimensional point set of its own, decorrelated from the other requests by a
 * permutation of the sample index seeded by (seed, pixel, dimension). So any number of
 * dimensions is supported with no direction-number table beyond Sobol's first two
 * dimensions, and a path that skips a request (NEE at a mirror) only loses
 * stratification, never uniformity. */
#include "sampling/sampler.h"

#include <string.h>

#include <math.h>
#if defined(__AVX2__)
#include <immintrin.h>
#endif

/* Sobol' generator matrices, as columns for index bits 0..31. Dimension 0 is the van der
 * Corput sequence (bit reversal); dimension 1 comes from the first primitive polynomial,
 * x + 1 (Joe & Kuo, new-joe-kuo-6.21201, d = 2: s = 1, a = 0, m_1 = 1), whose recurrence
 * v_k = v_{k-1} ^ (v_{k-1} >> 1) gives Pascal's matrix mod 2. Together they form a
 * (0, 2)-sequence in base 2: every aligned run of 2^m points has one point in each
 * elementary interval of area 2^-m (Niederreiter 1992, ch. 4). */
static const uint32_t SOBOL_DIM1[32] = {
    0x80000000u, 0xc0000000u, 0xa0000000u, 0xf0000000u, 0x88000000u, 0xcc000000u,
    0xaa000000u, 0xff000000u, 0x80800000u, 0xc0c00000u, 0xa0a00000u, 0xf0f00000u,
    0x88880000u, 0xcccc0000u, 0xaaaa0000u, 0xffff0000u, 0x80008000u, 0xc000c000u,
    0xa000a000u, 0xf000f000u, 0x88008800u, 0xcc00cc00u, 0xaa00aa00u, 0xff00ff00u,
    0x80808080u, 0xc0c0c0c0u, 0xa0a0a0a0u, 0xf0f0f0f0u, 0x88888888u, 0xccccccccu,
    0xaaaaaaaau, 0xffffffffu,
};

static inline uint32_t reverse_bits(uint32_t x)
{
    x = ((x >> 1) & 0x55555555u) | ((x & 0x55555555u) << 1);
    x = ((x >> 2) & 0x33333333u) | ((x & 0x33333333u) << 2);
    x = ((x >> 4) & 0x0f0f0f0fu) | ((x & 0x0f0f0f0fu) << 4);
    x = ((x >> 8) & 0x00ff00ffu) | ((x & 0x00ff00ffu) << 8);
    return (x >> 16) | (x << 16);
}

uint32_t sobol_sample(uint32_t index, int dim)
{
    if (dim == 0) return reverse_bits(index);
    uint32_t x = 0;
    for (int b = 0; index; b++, index >>= 1)
        if (index & 1u) x ^= SOBOL_DIM1[b];
    return x;
}

/* Burley, "Practical Hash-based Owen Scrambling", JCGT 9(4) 2020: in bit-reversed order,
 * a hash in which each bit depends only on the bits below it is a nested uniform scramble
 * (Owen 1995). The hash is Laine and Karras's (2011) as improved by Vegdahl (2021), the one
 * pbrt-v4's FastOwenScrambler uses. */
uint32_t owen_scramble(uint32_t x, uint32_t seed)
{
    return reverse_bits(owen_hash(reverse_bits(x), seed));
}

/* Kensler, "Correlated Multi-Jittered Sampling", Pixar TM 13-01 (2013), listing 3: a hash
 * that is a bijection on the next power of two, cycle-walked down to [0, n). */
uint32_t permute_index(uint32_t i, uint32_t n, uint32_t p)
{
    uint32_t w = n - 1u;
    w |= w >> 1;
    w |= w >> 2;
    w |= w >> 4;
    w |= w >> 8;
    w |= w >> 16;
    do {
        i ^= p;
        i *= 0xe170893du;
        i ^= p >> 16;
        i ^= (i & w) >> 4;
        i ^= p >> 8;
        i *= 0x0929eb3fu;
        i ^= p >> 23;
        i ^= (i & w) >> 1;
        i *= 1u | p >> 27;
        i *= 0x6935fa69u;
        i ^= (i & w) >> 11;
        i *= 0x74dcb303u;
        i ^= (i & w) >> 2;
        i *= 0x9e501cc3u;
        i ^= (i & w) >> 2;
        i *= 0xc860a3dfu;
        i &= w;
        i ^= i >> 5;
    } while (i >= n);
    return (i + p) % n;
}

/* 32-bit fraction to a float in [0, 1): 24 bits, so 1.0f is never returned. */
static inline float u32_to_float(uint32_t x) { return (float)(x >> 8) * 0x1p-24f; }

/* (stratum + jitter) / n, jitter a 32-bit fraction, as a float inside the stratum
 * [stratum / n, (stratum + 1) / n): rounding to float may cross either end (and reach
 * 1.0f), so it is stepped back in. */
static inline float stratum_float(uint32_t stratum, uint32_t jitter, uint32_t n)
{
    float v = (float)(((double)stratum + (double)jitter * 0x1p-32) / (double)n);
    while ((double)v * n >= (double)stratum + 1.0) v = nextafterf(v, 0.0f);
    while ((double)v * n < (double)stratum) v = nextafterf(v, 1.0f);
    return v;
}

/* Every scramble and permutation of one request derives from this. */
static inline uint64_t dim_key(const Sampler *s)
{
    return mix64(s->key ^ ((uint64_t)s->dim + 1u) * 0x9e3779b97f4a7c15ULL);
}

/* 2D strata: nx x (spp / nx) with nx the largest divisor of spp not above its square root,
 * so every sample index owns exactly one cell: 16 -> 4 x 4, 32 -> 4 x 8, a prime p -> 1 x p
 * (plain 1D stratification in y: choose square or power-of-two counts). */
static uint32_t strata_nx(uint32_t spp)
{
    uint32_t nx = 1;
    for (uint32_t d = 1; d <= spp / d; d++)
        if (spp % d == 0) nx = d;
    return nx;
}

/* zsobol: point k's permutation and scrambles from one 64-bit hash of (seed, k) and one
 * more mix of it; the rest are cheap derivations. */
static ZSobolDim zsobol_dim_hashed(uint64_t key, uint32_t k)
{
    const uint64_t DIGIT_HI = 0x5555555555555555ULL; /* reversed index: each digit's high bit */
    uint64_t h = mix64(key + (uint64_t)k * 0x9e3779b97f4a7c15ULL), h2 = mix64(h);
    ZSobolDim d;
    d.swap = h & DIGIT_HI;
    d.shear = (h >> 1) & (h2 | ((h2 >> 1) & (h2 >> 3))) & DIGIT_HI; /* P = 1/2 * 5/8 */
    d.add = h2;
    d.mul = (h ^ (h2 << 17)) | 1u;
    d.seed = (uint32_t)(h >> 32);
    d.seed_y = (uint32_t)(h2 >> 32);
    return d;
}

static void zsobol_lanes_set(ZSobolLanes *b, uint32_t j, ZSobolDim d)
{
    b->swap[j] = d.swap;
    b->shear[j] = d.shear;
    b->add[j] = d.add;
    b->mul[j] = d.mul;
    b->seed[j] = d.seed;
    b->seed_y[j] = d.seed_y;
}

SamplerSetup sampler_setup(CstSampler type, uint64_t seed, uint32_t spp, int width, int height)
{
    SamplerSetup u;
    memset(&u, 0, sizeof u);
    u.type = type == CST_SAMPLER_DEFAULT ? CST_SAMPLER_ZSOBOL : type;
    u.seed = seed;
    u.spp = spp;
    u.nx = 1;
    u.width = 1;
    if (u.type == CST_SAMPLER_STRATIFIED) u.nx = strata_nx(spp);
    if (u.type == CST_SAMPLER_ZSOBOL) {
        int side = width > height ? width : height, log2_side = 0;
        while (log2_side < 16 && (1 << log2_side) < side) log2_side++;
        u.width = width > 0 ? (uint32_t)width : 1u;
        u.morton_bits = 2u * (uint32_t)log2_side;
        u.zkey = mix64(seed ^ 0x2d358dccaa6c78a5ULL);
        for (uint32_t k = 0; k < ZSOBOL_TABLE; k++)
            zsobol_lanes_set(&u.zblocks[k / ZSOBOL_LANES], k % ZSOBOL_LANES, zsobol_dim_hashed(u.zkey, k));
    }
    return u;
}

ZSobolDim zsobol_dim(const SamplerSetup *u, uint32_t k)
{
    if (k >= ZSOBOL_TABLE) return zsobol_dim_hashed(u->zkey, k);
    const ZSobolLanes *b = &u->zblocks[k / ZSOBOL_LANES];
    uint32_t j = k % ZSOBOL_LANES;
    ZSobolDim d = {b->swap[j], b->shear[j], b->add[j], b->mul[j], b->seed[j], b->seed_y[j]};
    return d;
}

/* Spreads the low 16 bits of v to the even bit positions (Morton order). */
static inline uint32_t spread_bits(uint32_t v)
{
    v &= 0xffffu;
    v = (v | (v << 8)) & 0x00ff00ffu;
    v = (v | (v << 4)) & 0x0f0f0f0fu;
    v = (v | (v << 2)) & 0x33333333u;
    return (v | (v << 1)) & 0x55555555u;
}

/* Bit reversal of a 64-bit word: a byte swap, then nibbles, pairs and bits (sampler_rev32
 * on 64 bits: 13 operations where two reverse_bits take 30). */
static inline uint64_t reverse_bits64(uint64_t x)
{
    x = __builtin_bswap64(x);
    x = ((x >> 4) & 0x0f0f0f0f0f0f0f0fULL) | ((x & 0x0f0f0f0f0f0f0f0fULL) << 4);
    x = ((x >> 2) & 0x3333333333333333ULL) | ((x & 0x3333333333333333ULL) << 2);
    return ((x >> 1) & 0x5555555555555555ULL) | ((x & 0x5555555555555555ULL) << 1);
}

/* zsobol's index of (pixel, index): from the top, the sample's block (index / 256), the
 * pixel's Morton code (x in the even bits, y in the odd ones), the index within the block;
 * so every base-4 digit is one bit of x and one of y, or two bits of the index. At most
 * 23 + 32 + 8 = 63 bits. */
static inline uint64_t morton_index(const SamplerSetup *u, uint64_t pixel, uint32_t index)
{
    uint32_t p = (uint32_t)pixel, x = p % u->width, y = p / u->width; /* pixel < 65536^2 */
    uint64_t code = spread_bits(x) | ((uint64_t)spread_bits(y) << 1);
    const uint32_t m = ZSOBOL_LOG2_BLOCK;
    return ((uint64_t)(index >> m) << (m + u->morton_bits)) | (code << m) | (index & ((1u << m) - 1u));
}

uint64_t zsobol_morton_index(const SamplerSetup *u, uint64_t pixel, uint32_t index)
{
    return morton_index(u, pixel, index);
}

/* zsobol_point for the ZSOBOL_LANES points of a block, the same integers in another order:
 * the 64-bit index permutations one by one (64-bit multiplies, scalar), then the 32-bit
 * rest, Owen scrambles and bit reversals, as ZSOBOL_LANES independent lanes of one SIMD
 * register (AVX2: bswap as a byte shuffle, vpmulld; elsewhere a loop the compiler
 * vectorises). One point at a time, that rest was ~80 scalar operations and three quarters
 * of zsobol's cost over independent (perf, docs/benchmarks.md). test_sampler checks it
 * against zsobol_point. */
#if defined(__AVX2__)
/* Bit reversal of 8 lanes: the byte swap and each byte's two nibbles reversed by table
 * (3 shuffles, 7 instructions, where the shift-and-mask steps GCC vectorises take 16). */
static inline __m256i rev32_x8(__m256i x)
{
    const __m256i bswap = _mm256_setr_epi8(3, 2, 1, 0, 7, 6, 5, 4, 11, 10, 9, 8, 15, 14, 13, 12, 3, 2, 1, 0, 7, 6,
                                           5, 4, 11, 10, 9, 8, 15, 14, 13, 12);
    const __m256i rev4 = _mm256_setr_epi8(0x0, 0x8, 0x4, 0xc, 0x2, 0xa, 0x6, 0xe, 0x1, 0x9, 0x5, 0xd, 0x3, 0xb, 0x7,
                                          0xf, 0x0, 0x8, 0x4, 0xc, 0x2, 0xa, 0x6, 0xe, 0x1, 0x9, 0x5, 0xd, 0x3, 0xb,
                                          0x7, 0xf);
    const __m256i nib = _mm256_set1_epi8(0x0f);
    x = _mm256_shuffle_epi8(x, bswap);
    __m256i lo = _mm256_shuffle_epi8(rev4, _mm256_and_si256(x, nib));
    __m256i hi = _mm256_shuffle_epi8(rev4, _mm256_and_si256(_mm256_srli_epi16(x, 4), nib));
    return _mm256_or_si256(_mm256_slli_epi16(lo, 4), hi); /* lo < 16: no carry across bytes */
}

/* owen_hash on 8 lanes. */
static inline __m256i owen_hash_x8(__m256i x, __m256i seed)
{
    x = _mm256_xor_si256(x, _mm256_mullo_epi32(x, _mm256_set1_epi32(0x3d20adea)));
    x = _mm256_add_epi32(x, seed);
    x = _mm256_mullo_epi32(x, _mm256_or_si256(_mm256_srli_epi32(seed, 16), _mm256_set1_epi32(1)));
    x = _mm256_xor_si256(x, _mm256_mullo_epi32(x, _mm256_set1_epi32(0x05526c56)));
    return _mm256_xor_si256(x, _mm256_mullo_epi32(x, _mm256_set1_epi32(0x53a22864)));
}

/* sobol1_reversed on 8 lanes. */
static inline __m256i sobol1_reversed_x8(__m256i i)
{
    i = _mm256_xor_si256(i, _mm256_and_si256(_mm256_srli_epi32(i, 1), _mm256_set1_epi32(0x55555555)));
    i = _mm256_xor_si256(i, _mm256_and_si256(_mm256_srli_epi32(i, 2), _mm256_set1_epi32(0x33333333)));
    i = _mm256_xor_si256(i, _mm256_and_si256(_mm256_srli_epi32(i, 4), _mm256_set1_epi32(0x0f0f0f0f)));
    i = _mm256_xor_si256(i, _mm256_and_si256(_mm256_srli_epi32(i, 8), _mm256_set1_epi32(0x00ff00ff)));
    return _mm256_xor_si256(i, _mm256_srli_epi32(i, 16));
}

/* sampler_u32_to_float on 8 lanes. */
static inline __m256 u32_to_float_x8(__m256i x)
{
    return _mm256_mul_ps(_mm256_cvtepi32_ps(_mm256_srli_epi32(x, 8)), _mm256_set1_ps(0x1p-24f));
}
#endif

static inline void zsobol_block(uint64_t zrev, const ZSobolLanes *b, float *out)
{
    uint32_t hi[ZSOBOL_LANES], lo[ZSOBOL_LANES];
    const uint32_t *zseed = b->seed, *zseed_y = b->seed_y;
    for (uint32_t k = 0; k < ZSOBOL_LANES; k++) {
        /* zsobol_permuted, on the struct of arrays (a vector load per field) */
        uint64_t z = zrev;
        uint64_t t = (z ^ (z >> 1)) & b->swap[k];
        z ^= t | (t << 1);
        z ^= (z >> 1) & b->shear[k];
        z ^= z * 0x6c50b47cdb8a36d6ULL;
        z += b->add[k];
        z *= b->mul[k];
        z ^= z * 0xb82f1e52c0a7e73cULL;
        hi[k] = (uint32_t)(z >> 32);
        lo[k] = (uint32_t)z;
    }
#if defined(__AVX2__)
    __m256i vi = rev32_x8(_mm256_loadu_si256((const __m256i *)hi));
    __m256i vlo = _mm256_loadu_si256((const __m256i *)lo);
    __m256i sx = _mm256_xor_si256(_mm256_loadu_si256((const __m256i *)zseed),
                                  _mm256_mullo_epi32(vlo, _mm256_set1_epi32((int)0x9e3779b9u)));
    __m256i sy = _mm256_xor_si256(sx, _mm256_loadu_si256((const __m256i *)zseed_y));
    __m256 vx = u32_to_float_x8(rev32_x8(owen_hash_x8(vi, sx)));
    __m256 vy = u32_to_float_x8(rev32_x8(owen_hash_x8(sobol1_reversed_x8(vi), sy)));
    /* Interleaved (x0 y0 x1 y1 ...): unpack gives x0 y0 x1 y1 | x4 y4 x5 y5 and
     * x2 y2 x3 y3 | x6 y6 x7 y7; the 128-bit halves are then put in order. */
    __m256 a = _mm256_unpacklo_ps(vx, vy), c = _mm256_unpackhi_ps(vx, vy);
    _mm256_storeu_ps(out, _mm256_permute2f128_ps(a, c, 0x20));
    _mm256_storeu_ps(out + 8, _mm256_permute2f128_ps(a, c, 0x31));
#else
    float x[ZSOBOL_LANES], y[ZSOBOL_LANES];
    for (uint32_t k = 0; k < ZSOBOL_LANES; k++) {
        uint32_t i = sampler_rev32(hi[k]);
        uint32_t sx = zseed[k] ^ (lo[k] * 0x9e3779b9u);
        x[k] = sampler_u32_to_float(sampler_rev32(owen_hash(i, sx)));
        y[k] = sampler_u32_to_float(sampler_rev32(owen_hash(sobol1_reversed(i), sx ^ zseed_y[k])));
    }
    for (uint32_t k = 0; k < ZSOBOL_LANES; k++) {
        out[2 * k] = x[k];
        out[2 * k + 1] = y[k];
    }
#endif
}

/* The block of dimensions that holds s->dim: from the setup's table, or past it (paths of
 * more than 8 bounces) from hashes computed here. */
void zsobol_fill(Sampler *s)
{
    const SamplerSetup *u = s->zsetup;
    uint32_t first = s->dim / ZSOBOL_BLOCK * ZSOBOL_LANES; /* the block's first point */
    s->zend = (first + ZSOBOL_LANES) * 2u;
    if (first + ZSOBOL_LANES <= ZSOBOL_TABLE) {
        zsobol_block(s->zrev, &u->zblocks[first / ZSOBOL_LANES], s->zval);
        return;
    }
    ZSobolLanes b;
    for (uint32_t k = 0; k < ZSOBOL_LANES; k++) zsobol_lanes_set(&b, k, zsobol_dim_hashed(u->zkey, first + k));
    zsobol_block(s->zrev, &b, s->zval);
}

void sampler_start(Sampler *s, const SamplerSetup *u, uint64_t pixel, uint32_t index)
{
    s->type = u->type;
    s->dim = 0;
    s->index = index;
    s->spp = u->spp;
    s->nx = u->nx;
    if (u->type == CST_SAMPLER_ZSOBOL) {
        s->key = 0;
        s->rng.state = s->rng.inc = 0; /* unseeded: sampler_continue_sample seeds it */
        s->pixel = pixel;
        s->zrev = reverse_bits64(morton_index(u, pixel, index));
        s->zsetup = u;
        s->zend = ZSOBOL_BLOCK;
        zsobol_block(s->zrev, &u->zblocks[0], s->zval);
        return;
    }
    pcg32_seed_sample(&s->rng, u->seed, pixel, index);
    s->key = mix64(mix64(u->seed ^ 0x5851f42d4c957f2dULL) + pixel * 0xd1b54a32d192ed03ULL);
    s->pixel = pixel;
    s->zrev = 0;
    s->zend = 0;
    s->zsetup = NULL;
}

/* Stratified, Sobol' or PSS only: sampler_1d/2d (sampler.h) draw the independent ones inline. */
float sampler_1d_ld(Sampler *s)
{
    if (s->type == SAMPLER_PSS) return pss_next(s->pss);
    uint64_t h = dim_key(s);
    s->dim++;
    if (s->type == CST_SAMPLER_STRATIFIED) {
        uint32_t jitter = (uint32_t)(mix64(h + s->index) >> 32);
        if (s->index >= s->spp) return u32_to_float(jitter); /* beyond the known count: no strata */
        return stratum_float(permute_index(s->index, s->spp, (uint32_t)h), jitter, s->spp);
    }
    /* Shuffling the index by an Owen scramble maps every aligned block of 2^m indices onto
     * another such block (Burley 2020 §4), so prefixes stay stratified. */
    uint32_t i = owen_scramble(s->index, (uint32_t)h);
    return u32_to_float(owen_scramble(sobol_sample(i, 0), (uint32_t)(h >> 32)));
}

Vec2 sampler_2d_ld(Sampler *s)
{
    if (s->type == SAMPLER_PSS) { /* x first, then y: two coordinates of the chain's stream */
        float x = pss_next(s->pss);
        float y = pss_next(s->pss);
        return v2(x, y);
    }
    uint64_t h = dim_key(s);
    s->dim += 2;
    if (s->type == CST_SAMPLER_STRATIFIED) {
        uint64_t j = mix64(h + s->index);
        uint32_t jx = (uint32_t)j, jy = (uint32_t)(j >> 32);
        if (s->index >= s->spp) return v2(u32_to_float(jx), u32_to_float(jy));
        uint32_t cell = permute_index(s->index, s->spp, (uint32_t)h), ny = s->spp / s->nx;
        return v2(stratum_float(cell % s->nx, jx, s->nx), stratum_float(cell / s->nx, jy, ny));
    }
    uint64_t h2 = mix64(h);
    uint32_t i = owen_scramble(s->index, (uint32_t)h);
    return v2(u32_to_float(owen_scramble(sobol_sample(i, 0), (uint32_t)(h >> 32))),
              u32_to_float(owen_scramble(sobol_sample(i, 1), (uint32_t)h2)));
}

/* The public name table (caustic.h): the sampler module owns its names. */
CstSampler cst_sampler_from_name(const char *name)
{
    if (strcmp(name, "independent") == 0) return CST_SAMPLER_INDEPENDENT;
    if (strcmp(name, "stratified") == 0) return CST_SAMPLER_STRATIFIED;
    if (strcmp(name, "sobol") == 0) return CST_SAMPLER_SOBOL;
    if (strcmp(name, "zsobol") == 0) return CST_SAMPLER_ZSOBOL;
    return CST_SAMPLER_DEFAULT;
}

const char *cst_sampler_name(CstSampler sampler)
{
    switch (sampler) {
    case CST_SAMPLER_INDEPENDENT: return "independent";
    case CST_SAMPLER_STRATIFIED: return "stratified";
    case CST_SAMPLER_SOBOL: return "sobol";
    case CST_SAMPLER_ZSOBOL: return "zsobol";
    case CST_SAMPLER_DEFAULT: break;
    }
    return "default";
}
