// dsreg — internal: sums over many terms, in parallel, whose bits depend neither on the threads
// nor on the run.
//
// An OpenMP reduction(+) adds each thread's partial sum into the result in the order the threads
// finish, over ranges that depend on the thread count: at three threads or more the same input
// gives sums that differ in their last bits from run to run, and at any two thread counts sums
// that differ. Here the terms are summed in blocks of kSumBlock consecutive indices, each block in
// index order on one thread, and the block sums in block order.
#pragma once

#include <algorithm>
#include <array>
#include <cstddef>
#include <cstdint>
#include <vector>

namespace dsreg::detail {

inline constexpr std::int64_t kSumBlock = 4096;

/// The number of blocks of n terms; block b holds the terms [b·kSumBlock, min(n, (b+1)·kSumBlock)).
inline std::int64_t sum_blocks(std::int64_t n) { return n > 0 ? (n + kSumBlock - 1) / kSumBlock : 0; }
inline std::int64_t block_first(std::int64_t b) { return b * kSumBlock; }
inline std::int64_t block_last(std::int64_t b, std::int64_t n) { return std::min(n, (b + 1) * kSumBlock); }

/// K sums over i < n at once: add(i, sums) adds term i into sums[0], …, sums[K − 1]. In parallel
/// over the blocks when there is more than one (add must be safe to call from several threads).
template <std::size_t K, class Add>
std::array<double, K> ordered_sums(std::int64_t n, Add add) {
    const std::int64_t blocks = sum_blocks(n);
    std::vector<std::array<double, K>> partial(static_cast<std::size_t>(blocks));
#pragma omp parallel for schedule(static) if (blocks > 1)
    for (std::int64_t b = 0; b < blocks; ++b) {
        std::array<double, K> sums{};
        for (std::int64_t i = block_first(b); i < block_last(b, n); ++i) add(i, sums);
        partial[static_cast<std::size_t>(b)] = sums;
    }
    std::array<double, K> total{};
    for (const std::array<double, K>& sums : partial)
        for (std::size_t k = 0; k < K; ++k) total[k] += sums[k];
    return total;
}

}  // namespace dsreg::detail
