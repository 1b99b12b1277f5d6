// SPDX-License-Identifier: Apache-2.0
// sample2DMany gives PixelSampler::sample2D's values bit for bit, with AVX2 and without, for any
// count (whole groups of eight lanes and the rest).
#include "tracing/sample_batch.h"

#include <gtest/gtest.h>

#include <cstring>
#include <vector>

namespace sharcbake {
namespace {

using Implementation = void (*)(const uint32_t*, const uint32_t*, size_t, uint32_t, glm::vec2*);

bool sameBits(glm::vec2 a, glm::vec2 b) { return std::memcmp(&a, &b, sizeof a) == 0; }

/// Samplers of many seeds, pixels and sample indices (0 and all-ones included), every dimension
/// from 0 to 40 and some far ones, counts 0 to 37.
void expectScalarValues(Implementation draw, const char* what) {
    std::vector<uint32_t> hashes, reversed;
    std::vector<PixelSampler> samplers;
    for (uint32_t i = 0; i < 37; ++i) {
        const PixelSampler s(hashUint32(i) % 5, i * 7919u, i == 36 ? 0xFFFFFFFFu : i * i * 131u);
        samplers.push_back(s);
        hashes.push_back(s.pixelHash());
        reversed.push_back(s.reversedSample());
    }
    std::vector<uint32_t> dimensions;
    for (uint32_t d = 0; d <= 40; ++d) dimensions.push_back(d);
    for (uint32_t d : {1000u, 65537u, 0x7FFFFFFFu, 0xFFFFFFFFu}) dimensions.push_back(d);
    for (size_t count = 0; count <= samplers.size(); ++count) {
        for (const uint32_t d : dimensions) {
            std::vector<glm::vec2> out(count + 1, glm::vec2(-1.0f));
            draw(hashes.data(), reversed.data(), count, d, out.data());
            for (size_t i = 0; i < count; ++i) {
                ASSERT_TRUE(sameBits(out[i], samplers[i].sample2D(d)))
                    << what << ": count " << count << ", lane " << i << ", dimension " << d;
            }
            EXPECT_EQ(out[count], glm::vec2(-1.0f)) << what << ": wrote past count " << count;
        }
    }
}

TEST(SampleBatch, DrawsTheScalarSamplersValues) {
    expectScalarValues(sample2DMany, "sample2DMany");
    expectScalarValues(detail::sample2DManyScalar, "scalar");
}

TEST(SampleBatch, Avx2LanesDrawTheScalarSamplersValues) {
    glm::vec2 probe;
    const uint32_t zero = 0;
    if (!detail::sample2DManyAvx2(&zero, &zero, 1, 0, &probe)) GTEST_SKIP() << "no AVX2 on this CPU";
    expectScalarValues([](const uint32_t* h, const uint32_t* r, size_t n, uint32_t d,
                          glm::vec2* out) { ASSERT_TRUE(detail::sample2DManyAvx2(h, r, n, d, out)); },
                       "AVX2");
}

TEST(SampleBatch, NextIsSampleOfTheStartDimensionOnwards) {
    PixelSampler stream(3, 12345, 77);
    const PixelSampler fixed = stream;
    stream.startDimension(9);
    for (uint32_t d = 9; d < 20; ++d) EXPECT_TRUE(sameBits(stream.next2D(), fixed.sample2D(d))) << d;
}

}  // namespace
}  // namespace sharcbake
