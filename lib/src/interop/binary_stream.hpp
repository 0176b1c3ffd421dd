// Little-endian binary fields (ASP .match, MicMac .dat), written and read field by field with no
// padding. Reading checks every byte against the end of the data: a truncated file is an InputError
// naming the file and the byte offset.
#pragma once
#include <cstdint>
#include <cstring>
#include <ostream>
#include <string>
#include <type_traits>

#include "tpkit/core/error.hpp"

namespace tpkit {

static_assert(sizeof(float) == 4 && sizeof(double) == 8, "IEEE float32 / float64 expected");

template <class T>
void put_le(std::ostream& os, T v) {
  static_assert(std::is_arithmetic<T>::value, "a number");
  unsigned char b[sizeof(T)];
  std::memcpy(b, &v, sizeof(T));
#if defined(__BYTE_ORDER__) && __BYTE_ORDER__ == __ORDER_BIG_ENDIAN__
  for (size_t i = 0; i < sizeof(T) / 2; ++i) std::swap(b[i], b[sizeof(T) - 1 - i]);
#endif
  os.write(reinterpret_cast<const char*>(b), sizeof(T));
}

class ByteReader {
 public:
  ByteReader(const std::string& data, std::string source) : data_(data), source_(std::move(source)) {}
  template <class T>
  T get(const char* what) {
    if (data_.size() - pos_ < sizeof(T))
      throw InputError(source_, 0, "truncated at byte " + std::to_string(pos_) + " (reading " + what + "; the file has " +
                                       std::to_string(data_.size()) + " bytes)");
    unsigned char b[sizeof(T)];
    std::memcpy(b, data_.data() + pos_, sizeof(T));
#if defined(__BYTE_ORDER__) && __BYTE_ORDER__ == __ORDER_BIG_ENDIAN__
    for (size_t i = 0; i < sizeof(T) / 2; ++i) std::swap(b[i], b[sizeof(T) - 1 - i]);
#endif
    T v;
    std::memcpy(&v, b, sizeof(T));
    pos_ += sizeof(T);
    return v;
  }
  size_t left() const { return data_.size() - pos_; }
  size_t offset() const { return pos_; }
  const std::string& source() const { return source_; }

 private:
  const std::string& data_;
  std::string source_;
  size_t pos_ = 0;
};

// The whole file as bytes; InputError when it cannot be read.
std::string read_binary_file(const std::string& path);

}  // namespace tpkit
