#pragma once
// One hash for keys that are short arrays of 64-bit words: integers (grid cells), or doubles by
// their bit patterns (the input coordinates that name a plane). The registry's and the plane
// book's plane tables and the twins' grid use it.

#include <array>
#include <bit>
#include <cstddef>
#include <cstdint>
#include <type_traits>

namespace tetcut {

// splitmix64's finaliser on each word, chained: every bit of every word reaches the result, so
// nearby doubles (differing in their last mantissa bits) and neighbouring cells spread over the
// buckets. Doubles are hashed by their bits: fold -0.0 into 0.0 in a key first, as == does.
struct WordsHash {
  template <typename Word, std::size_t N>
  std::size_t operator()(const std::array<Word, N>& words) const {
    static_assert(sizeof(Word) == 8 && std::is_trivially_copyable_v<Word>, "a key of 64-bit words");
    std::uint64_t h = 0x9e3779b97f4a7c15ULL;
    for (const Word& word : words) {
      std::uint64_t z = std::bit_cast<std::uint64_t>(word) + 0x9e3779b97f4a7c15ULL + (h << 6) + (h >> 2);
      z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ULL;
      z = (z ^ (z >> 27)) * 0x94d049bb133111ebULL;
      h ^= z ^ (z >> 31);
    }
    return static_cast<std::size_t>(h);
  }
};

}  // namespace tetcut
