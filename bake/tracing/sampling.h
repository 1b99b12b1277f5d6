// SPDX-License-Identifier: Apache-2.0
/// @file sampling.h
/// @brief Deterministic sample generation and the warps that turn uniform samples into
/// directions and points.
///
/// Every random number the renderer uses is a pure function of (seed, pixel, sample index,
/// dimension). Nothing depends on which thread runs which pixel, so images and caches are
/// identical for any thread count.
///
/// The sequence is Owen-scrambled Sobol in 2D pairs with per-pixel, per-pair shuffling
/// (Burley 2020, "Practical Hash-based Owen Scrambling"): each dimension pair is a well
/// stratified (0,2)-sequence within a pixel, and pixels and pairs are decorrelated by hashing.
#pragma once

#include <glm/glm.hpp>

#include <cmath>
#include <cstdint>

namespace sharcbake {

inline constexpr float kPi = 3.14159265358979323846f;
inline constexpr float kInvPi = 0.318309886183790671538f;
inline constexpr float kOneMinusEpsilon = 0x1.fffffep-1f;

// --- Integer hashing -------------------------------------------------------------------------

/// 32-bit avalanche hash (a PCG-style output permutation); good enough to seed scrambles.
inline uint32_t hashUint32(uint32_t x) {
    uint32_t state = x * 747796405u + 2891336453u;
    uint32_t word = ((state >> ((state >> 28u) + 4u)) ^ state) * 277803737u;
    return (word >> 22u) ^ word;
}

/// Combines values into one hash; order matters.
inline uint32_t hashCombine(uint32_t seed, uint32_t value) {
    return hashUint32(seed ^ (value + 0x9e3779b9u + (seed << 6) + (seed >> 2)));
}

constexpr uint32_t reverseBits(uint32_t x) {
    x = (x << 16) | (x >> 16);
    x = ((x & 0x00ff00ffu) << 8) | ((x & 0xff00ff00u) >> 8);
    x = ((x & 0x0f0f0f0fu) << 4) | ((x & 0xf0f0f0f0u) >> 4);
    x = ((x & 0x33333333u) << 2) | ((x & 0xccccccccu) >> 2);
    x = ((x & 0x55555555u) << 1) | ((x & 0xaaaaaaaau) >> 1);
    return x;
}

/// Laine-Karras style hash that only lets higher bits depend on lower bits; applied to
/// bit-reversed values it is a nested uniform (Owen) scramble.
inline uint32_t laineKarrasPermutation(uint32_t x, uint32_t seed) {
    x += seed;
    x ^= x * 0x6c50b47cu;
    x ^= x * 0xb82f1e52u;
    x ^= x * 0xc7afe638u;
    x ^= x * 0x8d22f6e6u;
    return x;
}

inline uint32_t nestedUniformScramble(uint32_t x, uint32_t seed) {
    return reverseBits(laineKarrasPermutation(reverseBits(x), seed));
}

/// Sobol dimension 0 (van der Corput) and dimension 1, as bit patterns in [0, 2^32).
inline uint32_t sobolDimension0(uint32_t index) { return reverseBits(index); }
constexpr uint32_t sobolDimension1(uint32_t index) {
    uint32_t result = 0;
    for (uint32_t v = 1u << 31; index != 0; index >>= 1, v ^= v >> 1) {
        if (index & 1u) result ^= v;
    }
    return result;
}

namespace detail {
/// reverseBits(sobolDimension1(b << 8k)) for each byte b of the index. Both maps are linear over
/// GF(2) (XORs of per-bit vectors), so the four bytes' entries XOR to the whole index's value.
struct ReversedSobol1Table {
    uint32_t byte[4][256];
};
constexpr ReversedSobol1Table makeReversedSobol1Table() {
    ReversedSobol1Table table{};
    for (uint32_t k = 0; k < 4; ++k) {
        for (uint32_t b = 0; b < 256; ++b) table.byte[k][b] = reverseBits(sobolDimension1(b << (8 * k)));
    }
    return table;
}
inline constexpr ReversedSobol1Table kReversedSobol1 = makeReversedSobol1Table();
}  // namespace detail

/// reverseBits(sobolDimension1(index)) by four table lookups instead of a loop over the bits.
inline uint32_t reversedSobolDimension1(uint32_t index) {
    const auto& t = detail::kReversedSobol1.byte;
    return t[0][index & 0xFFu] ^ t[1][(index >> 8) & 0xFFu] ^ t[2][(index >> 16) & 0xFFu] ^ t[3][index >> 24];
}

/// Maps 32 random bits to a float in [0, 1).
inline float bitsToUnitFloat(uint32_t bits) { return float(bits >> 8) * 0x1p-24f; }

/// A uniform number in [0, 1) from a seed and two indices: for values that are not per-pixel
/// samples (camera placement, probes before a bake), deterministic and independent of any sampler.
inline float hashToUnitFloat(uint32_t seed, uint32_t a, uint32_t b) {
    return bitsToUnitFloat(hashCombine(hashCombine(hashUint32(seed), a), b));
}

// --- The per-pixel sampler ---------------------------------------------------------------------

/// Sample stream for one (pixel, sample index). Dimensions are consumed in a fixed order by the
/// integrator, so the k-th call returns the same value whatever else happens in the program.
class PixelSampler {
public:
    /// @param seed       the user's seed (--seed)
    /// @param pixel_id   a unique id of the pixel (or update path) within the pass
    /// @param sample     the sample (or iteration) index
    PixelSampler(uint32_t seed, uint32_t pixel_id, uint32_t sample)
        : PixelSampler(hashCombine(hashUint32(seed), pixel_id), reverseBits(sample)) {}
    /// The sampler whose pixelHash() and reversedSample() are these (sample_batch.h).
    PixelSampler(uint32_t pixel_hash, uint32_t reversed_sample)
        : pixel_hash_(pixel_hash), reversed_sample_(reversed_sample) {}

    /// What a draw depends on besides its dimension (sample_batch.h draws for many at once).
    uint32_t pixelHash() const { return pixel_hash_; }
    uint32_t reversedSample() const { return reversed_sample_; }

    /// Starts the dimension stream at a fixed offset, e.g. one block of dimensions per bounce,
    /// so that a path's bounce k always uses the same dimensions whatever earlier bounces used.
    void startDimension(uint32_t dimension) { dimension_ = dimension; }

    glm::vec2 next2D() { return sample2D(dimension_++); }

    /// The pair of dimension `dimension` (and dimension + 1 of the 1D view), without moving the
    /// stream: next2D() is sample2D(d) for d = the start dimension, d + 1, ... A pure function, so
    /// code that knows which dimensions it will need can draw them for many samplers in one
    /// loop, where the long chains of dependent multiplies of different samplers overlap.
    glm::vec2 sample2D(uint32_t dimension) const {
        const uint32_t pair_seed = hashCombine(pixel_hash_, dimension);
        // nestedUniformScramble(sample, pair_seed), with the sample's reversal done once.
        const uint32_t index = reverseBits(laineKarrasPermutation(reversed_sample_, pair_seed));
        // nestedUniformScramble(v) reverses v's bits first; sobolDimension0 is itself a reversal,
        // and dimension 1 comes reversed from its table: the same values, three reversals fewer.
        const uint32_t x = reverseBits(laineKarrasPermutation(index, hashCombine(pair_seed, 1u)));
        const uint32_t y = reverseBits(laineKarrasPermutation(reversedSobolDimension1(index), hashCombine(pair_seed, 2u)));
        return {bitsToUnitFloat(x), bitsToUnitFloat(y)};
    }

    float next1D() { return next2D().x; }

private:
    uint32_t pixel_hash_;
    uint32_t reversed_sample_;
    uint32_t dimension_ = 0;
};

// --- Warps -------------------------------------------------------------------------------------

/// Orthonormal basis around a unit vector n (Duff et al. 2017, branchless).
struct Frame {
    glm::vec3 t, b, n;
    explicit Frame(glm::vec3 normal) : n(normal) {
        const float sign = std::copysign(1.0f, normal.z);
        const float a = -1.0f / (sign + normal.z);
        const float bxy = normal.x * normal.y * a;
        t = {1.0f + sign * normal.x * normal.x * a, sign * bxy, -sign * normal.x};
        b = {bxy, sign + normal.y * normal.y * a, -normal.y};
    }
    glm::vec3 toWorld(glm::vec3 v) const { return v.x * t + v.y * b + v.z * n; }
    glm::vec3 toLocal(glm::vec3 v) const { return {glm::dot(v, t), glm::dot(v, b), glm::dot(v, n)}; }
};

/// Concentric square-to-disk map (Shirley-Chiu): area preserving, low distortion.
inline glm::vec2 sampleUniformDiskConcentric(glm::vec2 u) {
    const glm::vec2 offset = 2.0f * u - 1.0f;
    if (offset.x == 0.0f && offset.y == 0.0f) return {0.0f, 0.0f};
    float r, theta;
    if (std::abs(offset.x) > std::abs(offset.y)) {
        r = offset.x;
        theta = 0.25f * kPi * (offset.y / offset.x);
    } else {
        r = offset.y;
        theta = 0.5f * kPi - 0.25f * kPi * (offset.x / offset.y);
    }
    return r * glm::vec2(std::cos(theta), std::sin(theta));
}

/// Cosine-weighted direction around +Z; pdf = cos(theta) / pi.
inline glm::vec3 sampleCosineHemisphere(glm::vec2 u) {
    const glm::vec2 d = sampleUniformDiskConcentric(u);
    const float z = std::sqrt(std::max(0.0f, 1.0f - d.x * d.x - d.y * d.y));
    return {d.x, d.y, z};
}

inline glm::vec3 sampleUniformSphere(glm::vec2 u) {
    const float z = 1.0f - 2.0f * u.x;
    const float r = std::sqrt(std::max(0.0f, 1.0f - z * z));
    const float phi = 2.0f * kPi * u.y;
    return {r * std::cos(phi), r * std::sin(phi), z};
}

/// Direction `i` of `count` spread evenly over the sphere (a spherical Fibonacci set: even heights,
/// golden-angle turns), +Y the first: no two alike, none exactly along an axis.
inline glm::vec3 sphericalFibonacciDirection(uint32_t i, uint32_t count) {
    const float y = 1.0f - 2.0f * (float(i) + 0.5f) / float(count);
    const float ring = std::sqrt(std::max(0.0f, 1.0f - y * y));
    const float turn = 2.39996323f * float(i);
    return {ring * std::cos(turn), y, ring * std::sin(turn)};
}

/// The 6 axis directions and the 8 diagonals: a coarse, exact set of directions around a point,
/// enough to tell a closed solid from open space or to find the walls of a room.
inline constexpr int kAxisAndDiagonalDirections = 14;
/// Direction `i` (0 to kAxisAndDiagonalDirections - 1) of that set: +X, -X, +Y, -Y, +Z, -Z, then
/// the diagonals, unit length.
inline glm::vec3 axisOrDiagonalDirection(int i) {
    static const glm::vec3 kDirections[kAxisAndDiagonalDirections] = {{1, 0, 0},   {-1, 0, 0},  {0, 1, 0},  {0, -1, 0},
                                                                      {0, 0, 1},   {0, 0, -1},  {1, 1, 1},  {1, 1, -1},
                                                                      {1, -1, 1},  {1, -1, -1}, {-1, 1, 1}, {-1, 1, -1},
                                                                      {-1, -1, 1}, {-1, -1, -1}};
    return glm::normalize(kDirections[i]);
}

/// Uniform point on a triangle as barycentrics (b1, b2) of vertices 1 and 2 (Heitz 2019's
/// low-distortion square-to-triangle map keeps the Sobol stratification).
inline glm::vec2 sampleUniformTriangle(glm::vec2 u) {
    float b0, b1;
    if (u.x < u.y) {
        b0 = u.x / 2.0f;
        b1 = u.y - b0;
    } else {
        b1 = u.y / 2.0f;
        b0 = u.x - b1;
    }
    return {b0, b1};
}

/// Power heuristic (beta = 2) for multiple importance sampling of two strategies.
inline float powerHeuristic(float pdf_a, float pdf_b) {
    const float a2 = pdf_a * pdf_a;
    const float b2 = pdf_b * pdf_b;
    if (!(a2 + b2 > 0.0f)) return 0.0f;
    if (std::isinf(a2)) return 1.0f;
    return a2 / (a2 + b2);
}

inline constexpr float kLuminanceRed = 0.2126f, kLuminanceGreen = 0.7152f, kLuminanceBlue = 0.0722f;
inline float luminance(glm::vec3 c) { return kLuminanceRed * c.x + kLuminanceGreen * c.y + kLuminanceBlue * c.z; }
/// luminance() in double, for a colour whose float32 luminance may overflow.
inline double luminanceInDouble(glm::vec3 c) {
    return double(kLuminanceRed) * double(c.x) + double(kLuminanceGreen) * double(c.y) +
           double(kLuminanceBlue) * double(c.z);
}
inline float maxComponent(glm::vec3 c) { return std::max(c.x, std::max(c.y, c.z)); }
inline bool isFiniteColor(glm::vec3 c) {
    return std::isfinite(c.x) && std::isfinite(c.y) && std::isfinite(c.z);
}

}  // namespace sharcbake
