#include "core/digest.h"

#include <OpenImageIO/hash.h>

namespace photomat {

std::uint64_t Digest64(std::span<const std::byte> bytes, std::uint64_t seed) {
  return OIIO::xxhash::XXH64(bytes.data(), bytes.size(), seed);
}

std::uint64_t Digest64(std::string_view text, std::uint64_t seed) {
  return Digest64(std::as_bytes(std::span(text.data(), text.size())), seed);
}

}  // namespace photomat
