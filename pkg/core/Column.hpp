// A growable array whose storage is shared by reference count.
//
// Why not a plain std::vector: Python receives NumPy *views* of node and tet
// arrays.  When a piece is added the arrays grow and a std::vector would move
// its storage, leaving any view a user still holds pointing at freed memory.
// A Column instead allocates a new buffer on growth and lets the old one live
// as long as some view references it (the view then shows stale data, never
// garbage or a crash).
#pragma once
#include <algorithm>
#include <cstddef>
#include <memory>
#include <vector>

namespace qdem {

template <class T>
class Column {
public:
    Column() : buf_(std::make_shared<std::vector<T>>()) {}

    std::size_t size() const { return buf_->size(); }
    T* data() { return buf_->data(); }
    const T* data() const { return buf_->data(); }
    T& operator[](std::size_t i) { return (*buf_)[i]; }
    const T& operator[](std::size_t i) const { return (*buf_)[i]; }

    // Grow (or shrink) to n entries, new entries set to fill.  Reallocation
    // creates a fresh buffer so outstanding views of the old one stay valid.
    void resize(std::size_t n, const T& fill = T()) {
        if (n <= buf_->capacity()) {
            buf_->resize(n, fill);
            return;
        }
        auto fresh = std::make_shared<std::vector<T>>();
        fresh->reserve(std::max(n, 2 * buf_->capacity()));
        fresh->assign(buf_->begin(), buf_->end());
        fresh->resize(n, fill);
        buf_ = std::move(fresh);
    }
    void assign(std::size_t n, const T& v) {
        resize(n);
        std::fill(buf_->begin(), buf_->end(), v);
    }
    void fill(const T& v) { std::fill(buf_->begin(), buf_->end(), v); }

    // Keeps the current buffer alive; handed to NumPy as the base object.
    std::shared_ptr<std::vector<T>> owner() const { return buf_; }

private:
    std::shared_ptr<std::vector<T>> buf_;
};

}  // namespace qdem
