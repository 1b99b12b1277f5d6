// SPDX-License-Identifier: Apache-2.0
#include "tracing/sample_batch.h"

#if defined(__x86_64__) && defined(__GNUC__)
#include <immintrin.h>
#define SHARCBAKE_HAVE_AVX2_BATCH 1
#endif

namespace sharcbake {
namespace detail {

void sample2DManyScalar(const uint32_t* pixel_hashes, const uint32_t* reversed_samples, size_t count,
                        uint32_t dimension, glm::vec2* out) {
    for (size_t i = 0; i < count; ++i) out[i] = PixelSampler(pixel_hashes[i], reversed_samples[i]).sample2D(dimension);
}

#if SHARCBAKE_HAVE_AVX2_BATCH
namespace {

// Each function is its scalar namesake in sampling.h on eight lanes.
// Always inlined into the one AVX2 function, so no AVX value crosses a call (no ABI question).
#define SHARCBAKE_AVX2 __attribute__((target("avx2"), always_inline))

SHARCBAKE_AVX2 inline __m256i mul(__m256i a, uint32_t b) { return _mm256_mullo_epi32(a, _mm256_set1_epi32(int(b))); }

SHARCBAKE_AVX2 inline __m256i hashUint32x8(__m256i x) {
    const __m256i state = _mm256_add_epi32(mul(x, 747796405u), _mm256_set1_epi32(int(2891336453u)));
    const __m256i shift = _mm256_add_epi32(_mm256_srli_epi32(state, 28), _mm256_set1_epi32(4));
    const __m256i word = mul(_mm256_xor_si256(_mm256_srlv_epi32(state, shift), state), 277803737u);
    return _mm256_xor_si256(_mm256_srli_epi32(word, 22), word);
}

SHARCBAKE_AVX2 inline __m256i hashCombinex8(__m256i seed, __m256i value) {
    const __m256i mixed = _mm256_add_epi32(_mm256_add_epi32(value, _mm256_set1_epi32(int(0x9e3779b9u))),
                                           _mm256_add_epi32(_mm256_slli_epi32(seed, 6), _mm256_srli_epi32(seed, 2)));
    return hashUint32x8(_mm256_xor_si256(seed, mixed));
}

SHARCBAKE_AVX2 inline __m256i laineKarrasx8(__m256i x, __m256i seed) {
    x = _mm256_add_epi32(x, seed);
    x = _mm256_xor_si256(x, mul(x, 0x6c50b47cu));
    x = _mm256_xor_si256(x, mul(x, 0xb82f1e52u));
    x = _mm256_xor_si256(x, mul(x, 0xc7afe638u));
    x = _mm256_xor_si256(x, mul(x, 0x8d22f6e6u));
    return x;
}

/// Swaps the bit groups of `width` bits selected by `low_mask` with their neighbours.
SHARCBAKE_AVX2 inline __m256i swapBits(__m256i x, int width, uint32_t low_mask) {
    const __m256i mask = _mm256_set1_epi32(int(low_mask));
    return _mm256_or_si256(_mm256_slli_epi32(_mm256_and_si256(x, mask), width),
                           _mm256_and_si256(_mm256_srli_epi32(x, width), mask));
}

SHARCBAKE_AVX2 inline __m256i reverseBitsx8(__m256i x) {
    // The bytes of each lane reversed by one shuffle, then the bits within each byte.
    const __m256i bytes = _mm256_setr_epi8(3, 2, 1, 0, 7, 6, 5, 4, 11, 10, 9, 8, 15, 14, 13, 12,  //
                                           3, 2, 1, 0, 7, 6, 5, 4, 11, 10, 9, 8, 15, 14, 13, 12);
    x = _mm256_shuffle_epi8(x, bytes);
    x = swapBits(x, 4, 0x0f0f0f0fu);
    x = swapBits(x, 2, 0x33333333u);
    return swapBits(x, 1, 0x55555555u);
}

/// kReversedSobol1.byte[k][byte k of index], gathered.
SHARCBAKE_AVX2 inline __m256i reversedSobolBytex8(__m256i index, int k) {
    const __m256i b = _mm256_and_si256(_mm256_srli_epi32(index, 8 * k), _mm256_set1_epi32(0xFF));
    return _mm256_i32gather_epi32(reinterpret_cast<const int*>(kReversedSobol1.byte[k]), b, 4);
}

SHARCBAKE_AVX2 inline __m256i reversedSobolDimension1x8(__m256i index) {
    return _mm256_xor_si256(_mm256_xor_si256(reversedSobolBytex8(index, 0), reversedSobolBytex8(index, 1)),
                            _mm256_xor_si256(reversedSobolBytex8(index, 2), reversedSobolBytex8(index, 3)));
}

SHARCBAKE_AVX2 inline __m256 bitsToUnitFloatx8(__m256i bits) {
    // bits >> 8 < 2^24: the conversion and the power-of-two scale are exact, as in the scalar.
    return _mm256_mul_ps(_mm256_cvtepi32_ps(_mm256_srli_epi32(bits, 8)), _mm256_set1_ps(0x1p-24f));
}

__attribute__((target("avx2"))) void sample2DManyAvx2Lanes(const uint32_t* pixel_hashes,
                                                           const uint32_t* reversed_samples, size_t count,
                                                           uint32_t dimension, glm::vec2* out) {
    const __m256i d = _mm256_set1_epi32(int(dimension));
    for (size_t i = 0; i < count; i += 8) {
        const __m256i pixel_hash = _mm256_loadu_si256(reinterpret_cast<const __m256i*>(pixel_hashes + i));
        const __m256i reversed_sample = _mm256_loadu_si256(reinterpret_cast<const __m256i*>(reversed_samples + i));
        const __m256i pair_seed = hashCombinex8(pixel_hash, d);
        const __m256i index = reverseBitsx8(laineKarrasx8(reversed_sample, pair_seed));
        const __m256i x = reverseBitsx8(laineKarrasx8(index, hashCombinex8(pair_seed, _mm256_set1_epi32(1))));
        const __m256i y = reverseBitsx8(
            laineKarrasx8(reversedSobolDimension1x8(index), hashCombinex8(pair_seed, _mm256_set1_epi32(2))));
        // (x0, y0, x1, y1, ...): unpack within 128-bit halves, then put the halves in order.
        const __m256 fx = bitsToUnitFloatx8(x), fy = bitsToUnitFloatx8(y);
        const __m256 low = _mm256_unpacklo_ps(fx, fy), high = _mm256_unpackhi_ps(fx, fy);
        float* o = reinterpret_cast<float*>(out + i);
        _mm256_storeu_ps(o, _mm256_permute2f128_ps(low, high, 0x20));
        _mm256_storeu_ps(o + 8, _mm256_permute2f128_ps(low, high, 0x31));
    }
}

}  // namespace
#endif

bool sample2DManyAvx2(const uint32_t* pixel_hashes, const uint32_t* reversed_samples, size_t count, uint32_t dimension,
                      glm::vec2* out) {
#if SHARCBAKE_HAVE_AVX2_BATCH
    static const bool available = __builtin_cpu_supports("avx2");
    if (!available) return false;
    static_assert(sizeof(glm::vec2) == 2 * sizeof(float), "out is read as packed float pairs");
    const size_t lanes = count - count % 8;
    sample2DManyAvx2Lanes(pixel_hashes, reversed_samples, lanes, dimension, out);
    sample2DManyScalar(pixel_hashes + lanes, reversed_samples + lanes, count - lanes, dimension, out + lanes);
    return true;
#else
    (void)pixel_hashes, (void)reversed_samples, (void)count, (void)dimension, (void)out;
    return false;
#endif
}

}  // namespace detail

void sample2DMany(const uint32_t* pixel_hashes, const uint32_t* reversed_samples, size_t count, uint32_t dimension,
                  glm::vec2* out) {
    if (!detail::sample2DManyAvx2(pixel_hashes, reversed_samples, count, dimension, out)) {
        detail::sample2DManyScalar(pixel_hashes, reversed_samples, count, dimension, out);
    }
}

}  // namespace sharcbake
