// Small volumes built in code for the tests, and checks of error messages.
#pragma once

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <functional>
#include <initializer_list>
#include <random>
#include <string>

#include "dsreg/error.hpp"
#include "dsreg/volume.hpp"

/// Expects `text` to contain `part` (e.g. an error message and the words it must have).
#define EXPECT_CONTAINS(text, part) EXPECT_NE(std::string(text).find(part), std::string::npos) << "message: " << (text)

namespace dsreg::test {

/// The message of the dsreg::Error thrown by `f`, or "" (test failure) if none is thrown.
template <typename F>
std::string error_of(F&& f) {
    try {
        f();
    } catch (const Error& e) {
        return e.what();
    }
    ADD_FAILURE() << "no dsreg::Error thrown";
    return "";
}

/// A volume of `dims` voxels (spacing 1, origin 0) whose object is {(i,j,k) : inside(i,j,k)}.
inline BinaryVolume make_volume(const Index3& dims, const std::function<bool(double, double, double)>& inside) {
    BinaryVolume v;
    v.grid.dims = dims;
    v.mask.assign(std::size_t(v.grid.voxel_count()), 0);
    for (std::int64_t k = 0; k < dims[2]; ++k)
        for (std::int64_t j = 0; j < dims[1]; ++j)
            for (std::int64_t i = 0; i < dims[0]; ++i)
                v.mask[std::size_t(v.grid.linear_index(i, j, k))] = inside(double(i), double(j), double(k)) ? 1 : 0;
    return v;
}

/// A volume holding exactly the listed voxels.
inline BinaryVolume make_voxels(const Index3& dims, std::initializer_list<Index3> voxels) {
    BinaryVolume v = make_volume(dims, [](double, double, double) { return false; });
    for (const Index3& x : voxels) v.mask[std::size_t(v.grid.linear_index(x[0], x[1], x[2]))] = 1;
    return v;
}

/// A label map of `dims` voxels (spacing 1, origin 0) whose voxel (i,j,k) has the value
/// label(i,j,k) (0 = background), indexed as read_label_volume would: values increasing.
inline LabelVolume make_labels(const Index3& dims, const std::function<std::int64_t(std::int64_t, std::int64_t, std::int64_t)>& label) {
    LabelVolume v;
    v.grid.dims = dims;
    std::vector<std::int64_t> raw(std::size_t(v.grid.voxel_count()));
    std::vector<std::int64_t> values = {0};
    for (std::int64_t k = 0; k < dims[2]; ++k)
        for (std::int64_t j = 0; j < dims[1]; ++j)
            for (std::int64_t i = 0; i < dims[0]; ++i) {
                const std::int64_t value = label(i, j, k);
                raw[std::size_t(v.grid.linear_index(i, j, k))] = value;
                if (value != 0) values.push_back(value);
            }
    std::sort(values.begin() + 1, values.end());
    values.erase(std::unique(values.begin() + 1, values.end()), values.end());
    v.values = values;
    v.labels.resize(raw.size());
    for (std::size_t q = 0; q < raw.size(); ++q)
        v.labels[q] = raw[q] == 0 ? 0u
                                  : std::uint32_t(std::lower_bound(values.begin() + 1, values.end(), raw[q]) - values.begin());
    return v;
}

/// The indicator of label index `label` of a label map.
inline BinaryVolume indicator(const LabelVolume& labels, std::uint32_t label) {
    BinaryVolume v;
    v.grid = labels.grid;
    v.mask.resize(labels.labels.size());
    for (std::size_t q = 0; q < v.mask.size(); ++q) v.mask[q] = labels.labels[q] == label ? 1 : 0;
    return v;
}

/// A label map with junctions cut into several parts: a ball of radius 9 split into three sectors
/// (labels 1, 2, 3 meeting along its axis: junction curves and points), a two-label cube in a
/// corner (a small component with a junction curve where both labels meet the background) and a
/// one-label ball of radius 2 in another corner.
inline LabelVolume sectors_and_small_parts() {
    return make_labels({30, 30, 30}, [](std::int64_t i, std::int64_t j, std::int64_t k) -> std::int64_t {
        const double x = double(i) - 14.5, y = double(j) - 14.5, z = double(k) - 14.5;
        if (x * x + y * y + z * z <= 81) {
            const double angle = std::atan2(y, x + 0.3 * z);
            return angle < -1.0 ? 1 : angle < 1.2 ? 2 : 3;
        }
        if (i >= 1 && i <= 4 && j >= 1 && j <= 3 && k >= 1 && k <= 3) return i <= 2 ? 4 : 5;
        const double a = double(i) - 26, b = double(j) - 26, c = double(k) - 3;
        return a * a + b * b + c * c <= 4 ? 6 : 0;
    });
}

/// Digital ball of radius r (voxel units) centred at c.
inline BinaryVolume make_ball(std::int64_t size, double r, double c) {
    return make_volume({size, size, size}, [=](double x, double y, double z) {
        return (x - c) * (x - c) + (y - c) * (y - c) + (z - c) * (z - c) <= r * r;
    });
}

/// `volume` with a share of the voxels next to its surface (6-neighbours of the other kind, off
/// the volume's border) flipped, fixed seed: the noisy digitizations of bench/accuracy.py.
inline BinaryVolume flip_voxels_next_to_surface(const BinaryVolume& volume, double share, unsigned seed) {
    BinaryVolume noisy = volume;
    std::mt19937 random(seed);
    std::uniform_real_distribution<double> uniform(0.0, 1.0);
    const Index3& d = volume.grid.dims;
    for (std::int64_t k = 1; k + 1 < d[2]; ++k)
        for (std::int64_t j = 1; j + 1 < d[1]; ++j)
            for (std::int64_t i = 1; i + 1 < d[0]; ++i) {
                const bool inside = volume.inside(i, j, k);
                const bool next = volume.inside(i - 1, j, k) != inside || volume.inside(i + 1, j, k) != inside ||
                                  volume.inside(i, j - 1, k) != inside || volume.inside(i, j + 1, k) != inside ||
                                  volume.inside(i, j, k - 1) != inside || volume.inside(i, j, k + 1) != inside;
                if (next && uniform(random) < share) noisy.mask[std::size_t(volume.grid.linear_index(i, j, k))] = !inside;
            }
    return noisy;
}

/// The message of the dsreg::Error thrown by `action`; a test failure if it throws nothing.
inline std::string error_message(const std::function<void()>& action) {
    try {
        action();
    } catch (const dsreg::Error& error) {
        return error.what();
    }
    ADD_FAILURE() << "expected a dsreg::Error";
    return "";
}

}  // namespace dsreg::test
