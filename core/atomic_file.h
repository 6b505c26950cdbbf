#pragma once

#include <filesystem>
#include <functional>
#include <string>
#include <string_view>

namespace photomat {

// Writes `path` whole or not at all: `write` is called with a temporary path in the same folder
// (same extension, so format-by-extension writers work), which is then flushed to disk and renamed
// over `path`. If `write` throws, or flushing fails (a full disk often shows up only here), the
// temporary file is removed and the error propagates as an Error naming `path`.
void WriteFileAtomically(const std::filesystem::path& path,
                         const std::function<void(const std::filesystem::path& temp)>& write);

// WriteFileAtomically for a text or binary blob.
void WriteTextFileAtomically(const std::filesystem::path& path, std::string_view contents);

// WriteTextFileAtomically of the bytes `serialize` returns (a file format's encoder); an Error it
// throws is reported as a fault of `path`.
void WriteSerializedAtomically(const std::filesystem::path& path,
                               const std::function<std::string()>& serialize);

// Reads a whole file; throws Error naming the file if it is missing or unreadable.
std::string ReadTextFile(const std::filesystem::path& path);

}  // namespace photomat
