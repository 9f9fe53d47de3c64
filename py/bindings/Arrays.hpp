// NumPy views of core arrays without copies.  The view's base object holds a
// reference to the column's buffer, so a view stays valid (if stale) even
// after the world grows and reallocates.
#pragma once
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>

#include <algorithm>
#include <memory>
#include <vector>

#include "core/Column.hpp"

namespace qdem::py_ {

namespace py = pybind11;

template <class T>
py::array columnView(const Column<T>& c, std::size_t offset, std::vector<py::ssize_t> shape, bool writable = true) {
    auto* keep = new std::shared_ptr<std::vector<T>>(c.owner());
    py::capsule base(keep, [](void* p) { delete static_cast<std::shared_ptr<std::vector<T>>*>(p); });
    T* data = (*keep)->data() + offset;
    py::array_t<T> a(shape, data, base);
    if (!writable) py::detail::array_proxy(a.ptr())->flags &= ~py::detail::npy_api::NPY_ARRAY_WRITEABLE_;
    return a;  // moved (C++20: implicit move to the base type)
}

// Copies an (n, k) array-like into a flat vector, with a clear error on shape.
template <class T>
std::vector<T> flatten(const py::array_t<T, py::array::c_style | py::array::forcecast>& a, py::ssize_t cols,
                       const char* what) {
    if (a.ndim() != 2 || a.shape(1) != cols)
        throw std::invalid_argument(std::string(what) + ": expected an array of shape (n, " + std::to_string(cols) +
                                    "), got ndim=" + std::to_string(a.ndim()));
    return std::vector<T>(a.data(), a.data() + a.size());
}

// Copies a flat vector into a new (n, cols) array (mesh nodes, tets, edges).
template <class T>
py::array_t<T> toArray(const std::vector<T>& v, py::ssize_t cols) {
    py::array_t<T> a({static_cast<py::ssize_t>(v.size()) / cols, cols});
    std::copy(v.begin(), v.end(), a.mutable_data());
    return a;
}

}  // namespace qdem::py_
