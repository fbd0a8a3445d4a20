// dsreg distributed — the global numbering of the vertices (distributed_stages.hpp).
#include <algorithm>

#include "distributed_stages.hpp"
#include "dsreg/error.hpp"
#include "mpi_exchange.hpp"

namespace dsreg::distributed {

VertexNumbering number_vertices(MPI_Comm comm, const SurfacePatch& patch, const BlockLayout& layout) {
    int rank = 0, size = 1;
    MPI_Comm_rank(comm, &rank);
    MPI_Comm_size(comm, &size);
    VertexNumbering numbering;
    const std::int64_t n = patch.vertex_count();
    numbering.index.assign(std::size_t(n), -1);
    std::vector<std::int64_t> owned_keys;  // ascending, as the patch's
    for (std::int64_t i = 0; i < n; ++i)
        if (patch.vertex_owned[std::size_t(i)]) owned_keys.push_back(patch.vertex_keys[std::size_t(i)]);
    numbering.owned = std::int64_t(owned_keys.size());
    MPI_Exscan(&numbering.owned, &numbering.first, 1, MPI_INT64_T, MPI_SUM, comm);
    if (rank == 0) numbering.first = 0;
    MPI_Allreduce(&numbering.owned, &numbering.total, 1, MPI_INT64_T, MPI_SUM, comm);

    // Ask each owner for the numbers of its vertices that this patch uses.
    std::vector<std::vector<std::int64_t>> asked(static_cast<std::size_t>(size));
    std::vector<std::vector<std::int32_t>> asking_vertex(static_cast<std::size_t>(size));
    std::int64_t next = numbering.first;
    for (std::int64_t i = 0; i < n; ++i) {
        const std::int64_t key = patch.vertex_keys[std::size_t(i)];
        if (patch.vertex_owned[std::size_t(i)]) {
            numbering.index[std::size_t(i)] = next++;
            continue;
        }
        const std::size_t owner = std::size_t(layout.block_of(key_voxel_of_vertex(layout.dims, key)));
        asked[owner].push_back(key);
        asking_vertex[owner].push_back(std::int32_t(i));
    }
    const std::vector<std::vector<std::int64_t>> requests = exchange_arrays(comm, asked);
    std::vector<std::vector<std::int64_t>> answers(static_cast<std::size_t>(size));
    std::int64_t unknown = 0;
    for (int r = 0; r < size; ++r)
        for (const std::int64_t key : requests[std::size_t(r)]) {
            const auto it = std::lower_bound(owned_keys.begin(), owned_keys.end(), key);
            const bool found = it != owned_keys.end() && *it == key;
            unknown += !found;
            answers[std::size_t(r)].push_back(found ? numbering.first + (it - owned_keys.begin()) : -1);
        }
    const std::vector<std::vector<std::int64_t>> replies = exchange_arrays(comm, answers);
    for (int r = 0; r < size; ++r)
        for (std::size_t q = 0; q < replies[std::size_t(r)].size(); ++q)
            numbering.index[std::size_t(asking_vertex[std::size_t(r)][q])] = replies[std::size_t(r)][q];
    std::int64_t unknown_anywhere = 0;
    MPI_Allreduce(&unknown, &unknown_anywhere, 1, MPI_INT64_T, MPI_SUM, comm);
    if (unknown_anywhere > 0)
        throw Error("block seams do not match: " + std::to_string(unknown_anywhere) +
                    " vertices of a block's halo are unknown to the block that should own them (internal error)");
    return numbering;
}

}  // namespace dsreg::distributed
