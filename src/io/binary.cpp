#include "io/binary.hpp"

#include <zlib.h>

#include <array>

namespace tetcut::io {
namespace {

constexpr char kAlphabet[] = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";

constexpr std::array<int, 256> make_decode_table() {
  std::array<int, 256> table{};
  for (int& v : table) v = -1;
  for (int i = 0; i < 64; ++i) table[static_cast<unsigned char>(kAlphabet[i])] = i;
  return table;
}
constexpr std::array<int, 256> kDecode = make_decode_table();

bool is_space(char c) { return c == ' ' || c == '\n' || c == '\r' || c == '\t'; }

}  // namespace

std::string base64_encode(std::string_view bytes) {
  std::string out;
  out.reserve((bytes.size() + 2) / 3 * 4);
  std::size_t i = 0;
  for (; i + 3 <= bytes.size(); i += 3) {
    const std::uint32_t v = (std::uint32_t(std::uint8_t(bytes[i])) << 16) |
                            (std::uint32_t(std::uint8_t(bytes[i + 1])) << 8) | std::uint8_t(bytes[i + 2]);
    out += kAlphabet[(v >> 18) & 63];
    out += kAlphabet[(v >> 12) & 63];
    out += kAlphabet[(v >> 6) & 63];
    out += kAlphabet[v & 63];
  }
  const std::size_t rest = bytes.size() - i;
  if (rest > 0) {
    std::uint32_t v = std::uint32_t(std::uint8_t(bytes[i])) << 16;
    if (rest == 2) v |= std::uint32_t(std::uint8_t(bytes[i + 1])) << 8;
    out += kAlphabet[(v >> 18) & 63];
    out += kAlphabet[(v >> 12) & 63];
    out += rest == 2 ? kAlphabet[(v >> 6) & 63] : '=';
    out += '=';
  }
  return out;
}

bool base64_decode(std::string_view text, std::size_t max_bytes, std::string& out, std::size_t* consumed) {
  std::size_t pos = 0;
  char group[4];
  int filled = 0;
  const std::size_t start_size = out.size();
  while (pos < text.size() && out.size() - start_size < max_bytes) {
    const char c = text[pos++];
    if (is_space(c)) continue;
    group[filled++] = c;
    if (filled < 4) continue;
    filled = 0;
    int padding = 0;
    std::uint32_t v = 0;
    for (int k = 0; k < 4; ++k) {
      int d = 0;
      if (group[k] == '=') {
        if (k < 2) return false;
        ++padding;
      } else {
        if (padding > 0) return false;
        d = kDecode[static_cast<unsigned char>(group[k])];
        if (d < 0) return false;
      }
      v = (v << 6) | static_cast<std::uint32_t>(d);
    }
    const char decoded[3] = {static_cast<char>((v >> 16) & 255), static_cast<char>((v >> 8) & 255),
                             static_cast<char>(v & 255)};
    out.append(decoded, static_cast<std::size_t>(3 - padding));
  }
  if (consumed != nullptr) *consumed = pos;
  if (out.size() - start_size > max_bytes) out.resize(start_size + max_bytes);
  return filled == 0 || out.size() - start_size >= max_bytes;
}

bool zlib_inflate(std::string_view compressed, std::size_t size, std::string& out) {
  const std::size_t start = out.size();
  out.resize(start + size);
  uLongf out_size = static_cast<uLongf>(size);
  const int rc = uncompress(reinterpret_cast<Bytef*>(out.data() + start), &out_size,
                            reinterpret_cast<const Bytef*>(compressed.data()), static_cast<uLong>(compressed.size()));
  return rc == Z_OK && out_size == size;
}

}  // namespace tetcut::io
