#pragma once

#include <cstdint>
#include <span>
#include <string_view>

namespace photomat {

// A 64-bit digest of bytes that is the same on every run and machine (xxHash's XXH64, as
// OpenImageIO exports it), for cache keys and done records. Not cryptographic. Several pieces
// chain: Digest64(b, Digest64(a)) digests a then b.
std::uint64_t Digest64(std::span<const std::byte> bytes, std::uint64_t seed = 0);
std::uint64_t Digest64(std::string_view text, std::uint64_t seed = 0);

}  // namespace photomat
