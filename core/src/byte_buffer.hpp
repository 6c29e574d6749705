// Flat byte buffers: trivially copyable values, and arrays of them as a
// 64-bit count followed by the values, in the order written. Split mesh
// files, the .pvtu scans ranks exchange and the job's MPI messages are made
// of them; each reader of them checks every count against the bytes left
// before it allocates, so that a damaged or hostile count is an error, not
// an allocation of terabytes.
#pragma once

#include <cstddef>
#include <cstdint>
#include <cstring>
#include <functional>
#include <string>
#include <string_view>
#include <type_traits>
#include <utility>
#include <vector>

namespace tetiso::detail {

// Appends to `bytes`, a std::string or a std::vector<std::byte>.
template <class Bytes>
class ByteWriter {
public:
    template <class T>
    void put(const T& value) {
        static_assert(std::is_trivially_copyable_v<T>);
        append(&value, sizeof(T));
    }
    template <class T>
    void put_array(const std::vector<T>& values) {
        static_assert(std::is_trivially_copyable_v<T>);
        put(static_cast<std::uint64_t>(values.size()));
        append(values.data(), values.size() * sizeof(T));
    }

    Bytes bytes;

private:
    void append(const void* data, std::size_t size) {
        const auto* first = static_cast<const typename Bytes::value_type*>(data);
        bytes.insert(bytes.end(), first, first + size);
    }
};

// Reads back what a ByteWriter wrote. Reading past the end calls
// `truncated` with the name of what was being read; it must throw.
class ByteReader {
public:
    ByteReader(std::string_view bytes, std::function<void(const char* what)> truncated)
        : bytes_(bytes), truncated_(std::move(truncated)) {}

    template <class T>
    T get(const char* what = "a value") {
        static_assert(std::is_trivially_copyable_v<T>);
        if (sizeof(T) > left()) truncated_(what);
        T value;
        std::memcpy(&value, bytes_.data() + at_, sizeof(T));
        at_ += sizeof(T);
        return value;
    }
    template <class T>
    std::vector<T> get_array(const char* what = "an array") {
        static_assert(std::is_trivially_copyable_v<T>);
        const auto count = get<std::uint64_t>();
        if (count > left() / sizeof(T)) truncated_(what);
        std::vector<T> values(static_cast<std::size_t>(count));
        // An empty vector's data() may be null, which memcpy must not get,
        // even for 0 bytes.
        if (count > 0) std::memcpy(values.data(), bytes_.data() + at_, values.size() * sizeof(T));
        at_ += values.size() * sizeof(T);
        return values;
    }
    // The next `size` bytes as they are.
    std::string_view get_bytes(std::size_t size, const char* what) {
        if (size > left()) truncated_(what);
        const std::string_view out = bytes_.substr(at_, size);
        at_ += size;
        return out;
    }
    std::size_t left() const { return bytes_.size() - at_; }

private:
    std::string_view bytes_;
    std::size_t at_ = 0;
    std::function<void(const char*)> truncated_;
};

} // namespace tetiso::detail
