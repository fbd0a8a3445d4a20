// dsreg — internal: disjoint sets of the indices 0 … n − 1 (union-find with path halving). The
// smallest index of a set is its root, whatever the order of the unions, so results never depend
// on it. `Index`: the stored type (std::uint32_t where the sets number in the tens of millions
// and memory counts, as for the surface's face corners).
#pragma once

#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <numeric>
#include <vector>

namespace dsreg::detail {

template <class Index = std::int64_t>
class DisjointSets {
public:
    explicit DisjointSets(std::size_t size) : parent_(size) { std::iota(parent_.begin(), parent_.end(), Index(0)); }

    Index find(Index x) {
        while (parent_[std::size_t(x)] != x) x = parent_[std::size_t(x)] = parent_[std::size_t(parent_[std::size_t(x)])];
        return x;
    }

    void unite(Index a, Index b) {
        a = find(a), b = find(b);
        if (a != b) parent_[std::size_t(std::max(a, b))] = std::min(a, b);
    }

    std::size_t size() const { return parent_.size(); }

private:
    std::vector<Index> parent_;
};

}  // namespace dsreg::detail
