// dsreg — internal: disjoint sets of the indices 0 … n − 1 (union-find with path halving; the
// smaller index is the root, so a set's root is its first member).
#pragma once

#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <numeric>
#include <vector>

namespace dsreg::detail {

class DisjointSets {
public:
    explicit DisjointSets(std::size_t size) : parent_(size) { std::iota(parent_.begin(), parent_.end(), std::int64_t(0)); }

    std::int64_t find(std::int64_t x) {
        while (parent_[std::size_t(x)] != x) x = parent_[std::size_t(x)] = parent_[std::size_t(parent_[std::size_t(x)])];
        return x;
    }

    void unite(std::int64_t a, std::int64_t b) {
        a = find(a), b = find(b);
        if (a != b) parent_[std::size_t(std::max(a, b))] = std::min(a, b);
    }

private:
    std::vector<std::int64_t> parent_;
};

}  // namespace dsreg::detail
