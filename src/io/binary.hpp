#pragma once
// Byte-level helpers for binary formats: endianness, base64, zlib.

#include <cstdint>
#include <cstring>
#include <string>
#include <string_view>

namespace tetcut::io {

enum class ByteOrder { kLittle, kBig };

/// Reads a T stored at `bytes[offset]` in the given byte order. The caller checks bounds.
template <typename T>
T load(const char* bytes, ByteOrder order) {
  unsigned char raw[sizeof(T)];
  std::memcpy(raw, bytes, sizeof(T));
  // This code runs on little-endian hosts (x86-64, arm64); big-endian data is byte-reversed.
  if (order == ByteOrder::kBig) {
    for (std::size_t i = 0; i < sizeof(T) / 2; ++i) std::swap(raw[i], raw[sizeof(T) - 1 - i]);
  }
  T value;
  std::memcpy(&value, raw, sizeof(T));
  return value;
}

template <typename T>
void store_le(std::string& out, T value) {
  char raw[sizeof(T)];
  std::memcpy(raw, &value, sizeof(T));
  out.append(raw, sizeof(T));
}

std::string base64_encode(std::string_view bytes);
/// Decodes base64 group by group, skipping whitespace, so that several independently encoded
/// (padded) streams written back to back decode as their concatenation, as VTK writes them.
/// Stops after `max_bytes` bytes. Returns false on a character outside the alphabet; `consumed`
/// receives the number of input characters used.
bool base64_decode(std::string_view text, std::size_t max_bytes, std::string& out, std::size_t* consumed = nullptr);

/// Inflates a zlib stream whose decompressed size is known. Returns false on corrupt data.
bool zlib_inflate(std::string_view compressed, std::size_t size, std::string& out);

}  // namespace tetcut::io
