// dsreg distributed — internal: moving plain arrays between ranks (trivially copyable elements,
// sent as bytes; counts beyond int are split into chunks).
#pragma once

#include <mpi.h>

#include <algorithm>
#include <climits>
#include <cstdint>
#include <string>
#include <type_traits>
#include <vector>

#include "dsreg/error.hpp"

namespace dsreg::distributed {

constexpr std::size_t kMaxMessageBytes = std::size_t(1) << 30;

/// `text` of `root`, on every rank.
inline void broadcast_string(MPI_Comm comm, std::string& text, int root) {
    std::uint64_t length = text.size();
    MPI_Bcast(&length, 1, MPI_UINT64_T, root, comm);
    text.resize(std::size_t(length));
    MPI_Bcast(text.data(), int(length), MPI_CHAR, root, comm);
}

/// Sends `count` elements to `destination` in messages of at most 1 GiB.
template <class T>
void send_array(MPI_Comm comm, const T* data, std::size_t count, int destination, int tag) {
    static_assert(std::is_trivially_copyable_v<T>);
    const char* bytes = reinterpret_cast<const char*>(data);
    const std::size_t total = count * sizeof(T);
    for (std::size_t start = 0; start < total; start += kMaxMessageBytes)
        MPI_Send(bytes + start, int(std::min(kMaxMessageBytes, total - start)), MPI_BYTE, destination, tag, comm);
}

/// Receives `count` elements sent by send_array.
template <class T>
void receive_array(MPI_Comm comm, T* data, std::size_t count, int source, int tag) {
    char* bytes = reinterpret_cast<char*>(data);
    const std::size_t total = count * sizeof(T);
    for (std::size_t start = 0; start < total; start += kMaxMessageBytes)
        MPI_Recv(bytes + start, int(std::min(kMaxMessageBytes, total - start)), MPI_BYTE, source, tag, comm, MPI_STATUS_IGNORE);
}

/// On `root`: every rank's `local`, in rank order; on the other ranks: empty.
template <class T>
std::vector<std::vector<T>> gather_arrays(MPI_Comm comm, const std::vector<T>& local, int root = 0) {
    int rank = 0, size = 1;
    MPI_Comm_rank(comm, &rank);
    MPI_Comm_size(comm, &size);
    const std::uint64_t count = local.size();
    std::vector<std::uint64_t> counts(static_cast<std::size_t>(rank == root ? size : 0));
    MPI_Gather(&count, 1, MPI_UINT64_T, counts.data(), 1, MPI_UINT64_T, root, comm);
    std::vector<std::vector<T>> gathered;
    if (rank != root) {
        send_array(comm, local.data(), local.size(), root, 17);
        return gathered;
    }
    gathered.resize(std::size_t(size));
    for (int r = 0; r < size; ++r) {
        if (r == root) {
            gathered[std::size_t(r)] = local;
            continue;
        }
        gathered[std::size_t(r)].resize(std::size_t(counts[std::size_t(r)]));
        receive_array(comm, gathered[std::size_t(r)].data(), gathered[std::size_t(r)].size(), r, 17);
    }
    return gathered;
}

/// Personalized all-to-all: rank r receives outgoing[r] of every rank, in rank order.
template <class T>
std::vector<std::vector<T>> exchange_arrays(MPI_Comm comm, const std::vector<std::vector<T>>& outgoing) {
    static_assert(std::is_trivially_copyable_v<T>);
    int size = 1;
    MPI_Comm_size(comm, &size);
    std::vector<int> send_bytes(static_cast<std::size_t>(size)), receive_bytes(static_cast<std::size_t>(size));
    std::vector<int> send_offsets(static_cast<std::size_t>(size)), receive_offsets(static_cast<std::size_t>(size));
    std::vector<char> sent;
    for (int r = 0; r < size; ++r) {
        const auto& part = outgoing[std::size_t(r)];
        if (part.size() * sizeof(T) + sent.size() > std::size_t(INT_MAX))
            throw Error("internal error: a vertex exchange between ranks exceeds 2 GiB");
        send_offsets[std::size_t(r)] = int(sent.size());
        send_bytes[std::size_t(r)] = int(part.size() * sizeof(T));
        const char* bytes = reinterpret_cast<const char*>(part.data());
        sent.insert(sent.end(), bytes, bytes + part.size() * sizeof(T));
    }
    MPI_Alltoall(send_bytes.data(), 1, MPI_INT, receive_bytes.data(), 1, MPI_INT, comm);
    std::size_t total = 0;
    for (int r = 0; r < size; ++r) {
        receive_offsets[std::size_t(r)] = int(total);
        total += std::size_t(receive_bytes[std::size_t(r)]);
    }
    std::vector<char> received(total);
    MPI_Alltoallv(sent.data(), send_bytes.data(), send_offsets.data(), MPI_BYTE, received.data(), receive_bytes.data(),
                  receive_offsets.data(), MPI_BYTE, comm);
    std::vector<std::vector<T>> incoming(static_cast<std::size_t>(size));
    for (int r = 0; r < size; ++r) {
        auto& part = incoming[std::size_t(r)];
        part.resize(std::size_t(receive_bytes[std::size_t(r)]) / sizeof(T));
        std::copy_n(received.data() + receive_offsets[std::size_t(r)], receive_bytes[std::size_t(r)], reinterpret_cast<char*>(part.data()));
    }
    return incoming;
}

}  // namespace dsreg::distributed
