// A case's result as bytes for distribute() and back, bit for bit (a double's 8 bytes, not its
// decimal text: NaN, infinities and the last bit survive). A type lists its fields once, in one
// function template that both directions call:
//
//   template <class Archive> void fields(Archive& a, Trial& t) { a(t.index, t.verdict, t.truth); }
//
// and archive(value) / unarchive(bytes, value) do the rest. Both ends are the same program, so the
// byte order and layout need no header.
#pragma once

#include <cstdint>
#include <cstring>
#include <optional>
#include <stdexcept>
#include <string>
#include <type_traits>
#include <vector>

namespace canalsim::cluster {

class ArchiveWriter {
 public:
  template <class... Values>
  void operator()(Values&... values) {
    (write(values), ...);
  }
  std::string take() { return std::move(bytes_); }

 private:
  template <class T>
  void write(T& value) {
    if constexpr (std::is_arithmetic_v<T> || std::is_enum_v<T>) {
      bytes_.append(reinterpret_cast<const char*>(&value), sizeof value);
    } else if constexpr (std::is_same_v<T, std::string>) {
      write_size(value.size());
      bytes_.append(value);
    } else if constexpr (requires { value.has_value(); }) {
      bool present = value.has_value();
      write(present);
      if (present) write(*value);
    } else if constexpr (requires { value.begin(); value.resize(0); }) {
      write_size(value.size());
      for (auto&& item : value) write_item(item);
    } else {
      fields(*this, value);
    }
  }
  template <class T>
  void write_item(T& item) {
    write(item);
  }
  void write_item(std::vector<bool>::reference item) {
    bool b = item;
    write(b);
  }
  void write_size(std::size_t n) {
    auto size = static_cast<std::uint64_t>(n);
    write(size);
  }

  std::string bytes_;
};

class ArchiveReader {
 public:
  explicit ArchiveReader(const std::string& bytes) : bytes_(bytes) {}
  template <class... Values>
  void operator()(Values&... values) {
    (read(values), ...);
  }
  bool at_end() const { return position_ == bytes_.size(); }

 private:
  template <class T>
  void read(T& value) {
    if constexpr (std::is_arithmetic_v<T> || std::is_enum_v<T>) {
      take(&value, sizeof value);
    } else if constexpr (std::is_same_v<T, std::string>) {
      value.resize(read_size());
      if (!value.empty()) take(value.data(), value.size());
    } else if constexpr (requires { value.has_value(); }) {
      bool present = false;
      read(present);
      if (present) {
        value.emplace();
        read(*value);
      } else {
        value.reset();
      }
    } else if constexpr (requires { value.begin(); value.resize(0); }) {
      value.resize(read_size());
      for (auto&& item : value) read_item(item);
    } else {
      fields(*this, value);
    }
  }
  template <class T>
  void read_item(T& item) {
    read(item);
  }
  void read_item(std::vector<bool>::reference item) {
    bool b = false;
    read(b);
    item = b;
  }
  std::size_t read_size() {
    std::uint64_t size = 0;
    read(size);
    if (size > bytes_.size() - position_) throw std::runtime_error("archive: a size past the end of the bytes");
    return static_cast<std::size_t>(size);
  }
  void take(void* out, std::size_t n) {
    if (n > bytes_.size() - position_) throw std::runtime_error("archive: read past the end of the bytes");
    std::memcpy(out, bytes_.data() + position_, n);
    position_ += n;
  }

  const std::string& bytes_;
  std::size_t position_ = 0;
};

template <class T>
std::string archive(T& value) {
  ArchiveWriter writer;
  writer(value);
  return writer.take();
}

// Throws std::runtime_error when the bytes do not hold exactly one T.
template <class T>
void unarchive(const std::string& bytes, T& value) {
  ArchiveReader reader(bytes);
  reader(value);
  if (!reader.at_end()) throw std::runtime_error("archive: bytes left after the value");
}

}  // namespace canalsim::cluster
