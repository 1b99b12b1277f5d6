// SPDX-License-Identifier: Apache-2.0
// Load and query throughput of the runtime library (docs/design.md §5 bars: open + validate >= 1 GB/s,
// >= 20 M lookups/s per core on a cache with 1 M live entries). Prints one JSON object.
// Usage: cache_runtime_bench [live_voxels (default 1000000)] [lookups (default 4000000)]
#include "synthetic_cache.h"

#include "sharcbake/cache_file.h"
#include "sharcbake/runtime.h"
#include "sharcbake/runtime_c.h"

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <random>
#include <vector>

using namespace sharcbake;

int main(int argc, char** argv) {
    const size_t live = argc > 1 ? size_t(std::strtoull(argv[1], nullptr, 10)) : 1000000;
    const size_t queries = argc > 2 ? size_t(std::strtoull(argv[2], nullptr, 10)) : 4000000;
    std::mt19937 rng(1234);  // also orders the queries below
    std::vector<Float3> points, normals;
    const CacheData data = makeSyntheticCache(live, 1u << 22, rng, points, normals);
    std::vector<uint8_t> bytes;
    std::string message;
    if (encodeCacheFile(data, &bytes, &message) != CacheFileStatus::kOk) {
        std::fprintf(stderr, "encode failed: %s\n", message.c_str());
        return 1;
    }
    using clock = std::chrono::steady_clock;
    CacheView view;
    double open_seconds = 1e30;
    for (int rep = 0; rep < 5; ++rep) {
        const auto t0 = clock::now();
        if (CacheView::openMemory(bytes.data(), bytes.size(), &view, nullptr) != CacheFileStatus::kOk) return 1;
        open_seconds = std::min(open_seconds, std::chrono::duration<double>(clock::now() - t0).count());
    }
    // Query points in random order (no locality), all hits.
    std::vector<uint32_t> order(queries);
    std::uniform_int_distribution<uint32_t> pick(0, uint32_t(live - 1));
    for (uint32_t& o : order) o = pick(rng);
    // Queries arrive as a stream (sequential arrays); the cache is hit in random order.
    std::vector<Float3> qp(queries), qn(queries);
    for (size_t j = 0; j < queries; ++j) {
        qp[j] = points[order[j]];
        qn[j] = normals[order[j]];
    }
    auto run = [&](size_t& hits, double& sum) {
        hits = 0;
        sum = 0.0;
        const auto t1 = clock::now();
        for (size_t j = 0; j < queries; ++j) {
            Float3 r;
            if (view.lookup(qp[j], qn[j], {0, 0, 0}, &r)) {
                ++hits;
                sum += r.x;
            }
        }
        return std::chrono::duration<double>(clock::now() - t1).count();
    };
    size_t hits = 0, hits_indexed = 0;
    double sum = 0.0, sum_indexed = 0.0;
    uint64_t key_acc = 0;
    const auto t2 = clock::now();
    for (size_t j = 0; j < queries; ++j) key_acc ^= view.keyFor(qp[j], qn[j], {0, 0, 0});
    const double key_seconds = std::chrono::duration<double>(clock::now() - t2).count();
    const double lookup_seconds = run(hits, sum);
    const auto t3 = clock::now();
    if (view.buildLookupIndex() != CacheFileStatus::kOk) return 1;
    const double index_seconds = std::chrono::duration<double>(clock::now() - t3).count();
    const double indexed_seconds = run(hits_indexed, sum_indexed);
    std::vector<Float3> out(queries);
    const auto t4 = clock::now();
    const size_t batch_hits = view.lookupBatch(queries, qp.data(), qn.data(), {0, 0, 0}, out.data());
    const double batch_seconds = std::chrono::duration<double>(clock::now() - t4).count();
    // Coherent stream: the same queries sorted by key (neighbouring surface points, as a frame's
    // pixels arrive), single lookups.
    std::vector<size_t> perm(queries);
    for (size_t j = 0; j < queries; ++j) perm[j] = j;
    std::vector<uint64_t> qkeys(queries);
    for (size_t j = 0; j < queries; ++j) qkeys[j] = view.keyFor(qp[j], qn[j], {0, 0, 0});
    std::sort(perm.begin(), perm.end(), [&](size_t a, size_t b) { return qkeys[a] < qkeys[b]; });
    std::vector<Float3> sp(queries), sn(queries);
    for (size_t j = 0; j < queries; ++j) {
        sp[j] = qp[perm[j]];
        sn[j] = qn[perm[j]];
    }
    size_t coherent_hits = 0;
    const auto t5 = clock::now();
    for (size_t j = 0; j < queries; ++j) {
        Float3 r;
        coherent_hits += view.lookup(sp[j], sn[j], {0, 0, 0}, &r) ? 1 : 0;
    }
    const double coherent_seconds = std::chrono::duration<double>(clock::now() - t5).count();
    std::printf("{\"batch_random_lookups_per_second\": %.4g, \"batch_hits\": %zu, "
                "\"coherent_lookups_per_second\": %.4g, \"coherent_hits\": %zu}\n",
                double(queries) / batch_seconds, batch_hits, double(queries) / coherent_seconds, coherent_hits);
    std::printf("{\"keys_per_second\": %.4g, \"key_checksum\": %llu, \"index_build_seconds\": %.4f, "
                "\"indexed_lookups_per_second\": %.4g, \"indexed_hits\": %zu}\n",
                double(queries) / key_seconds, (unsigned long long)key_acc, index_seconds,
                double(queries) / indexed_seconds, hits_indexed);
    std::printf("{\"live_voxels\": %zu, \"file_bytes\": %zu, \"bytes_per_voxel\": %.2f, "
                "\"open_validate_seconds\": %.6f, \"open_validate_gb_per_s\": %.3f, "
                "\"lookups\": %zu, \"hits\": %zu, \"binary_search_lookups_per_second\": %.4g, \"checksum\": %g}\n",
                live, bytes.size(), double(bytes.size()) / double(live), open_seconds,
                double(bytes.size()) / open_seconds / 1e9, queries, hits, double(queries) / lookup_seconds, sum);
    // The same random batch through the C API, before and after sharcbake_cache_build_lookup_index.
    sharcbake_cache* c_cache = nullptr;
    if (sharcbake_cache_open_memory(bytes.data(), bytes.size(), &c_cache, nullptr, nullptr, 0) != SHARCBAKE_OK)
        return 1;
    const float origin[3] = {0.0f, 0.0f, 0.0f};
    auto c_batch = [&](size_t& c_hits) {
        const auto t = clock::now();
        c_hits = sharcbake_cache_lookup_batch(c_cache, queries, &qp[0].x, &qn[0].x, origin, &out[0].x, nullptr, 0);
        return std::chrono::duration<double>(clock::now() - t).count();
    };
    size_t c_hits = 0, c_hits_indexed = 0;
    const double c_seconds = c_batch(c_hits);
    if (sharcbake_cache_build_lookup_index(c_cache) != SHARCBAKE_OK) return 1;
    const double c_indexed_seconds = c_batch(c_hits_indexed);
    sharcbake_cache_close(c_cache);
    std::printf("{\"c_batch_binary_search_lookups_per_second\": %.4g, \"c_batch_indexed_lookups_per_second\": %.4g}\n",
                double(queries) / c_seconds, double(queries) / c_indexed_seconds);
    return hits == queries && hits_indexed == queries && c_hits == queries && c_hits_indexed == queries ? 0 : 1;
}
