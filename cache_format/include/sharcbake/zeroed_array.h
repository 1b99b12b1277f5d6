// SPDX-License-Identifier: Apache-2.0
/// @file zeroed_array.h
/// @brief A fixed-size array that starts as all-zero bytes and costs memory only where written.
#pragma once

#include <cstddef>
#include <cstdlib>
#include <new>
#include <type_traits>
#include <utility>

namespace sharcbake {

/// A fixed-size array of `T` whose elements start as all-zero bytes, allocated with calloc.
/// Large blocks come from the kernel's zero pages, so a hash table of millions of slots costs
/// memory and set-up time only for the pages its keys touch: a bake of a small scene into the
/// SDK's 2^22 slots touches a few percent of them. A std::vector would write every element.
///
/// T must be valid as all-zero bytes (integers, floats, std::atomic of them, aggregates of
/// those whose defaults are zero) and trivially destructible.
template <typename T> class ZeroedArray {
    static_assert(std::is_trivially_destructible_v<T>, "ZeroedArray never runs destructors");

public:
    ZeroedArray() = default;
    /// Throws std::bad_alloc if the memory is not there.
    explicit ZeroedArray(size_t size) : size_(size) {
        if (size == 0) return;
        data_ = static_cast<T*>(std::calloc(size, sizeof(T)));
        if (!data_) throw std::bad_alloc();
    }
    ZeroedArray(ZeroedArray&& other) noexcept
        : data_(std::exchange(other.data_, nullptr)), size_(std::exchange(other.size_, 0)) {}
    ZeroedArray& operator=(ZeroedArray&& other) noexcept {
        if (this != &other) {
            std::free(data_);
            data_ = std::exchange(other.data_, nullptr);
            size_ = std::exchange(other.size_, 0);
        }
        return *this;
    }
    ZeroedArray(const ZeroedArray&) = delete;
    ZeroedArray& operator=(const ZeroedArray&) = delete;
    ~ZeroedArray() { std::free(data_); }

    size_t size() const { return size_; }
    T* data() { return data_; }
    const T* data() const { return data_; }
    T& operator[](size_t i) { return data_[i]; }
    const T& operator[](size_t i) const { return data_[i]; }
    T* begin() { return data_; }
    T* end() { return data_ + size_; }
    const T* begin() const { return data_; }
    const T* end() const { return data_ + size_; }

private:
    T* data_ = nullptr;
    size_t size_ = 0;
};

}  // namespace sharcbake
