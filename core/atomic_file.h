#pragma once

#include <filesystem>
#include <functional>
#include <future>
#include <string>
#include <string_view>

namespace photomat {

// Writes `path` whole or not at all: `write` is called with a temporary path in the same folder
// (same extension, so format-by-extension writers work), which is then flushed to disk and renamed
// over `path`. If `write` throws, or flushing fails (a full disk often shows up only here), the
// temporary file is removed and the error propagates as an Error naming `path`.
void WriteFileAtomically(const std::filesystem::path& path,
                         const std::function<void(const std::filesystem::path& temp)>& write);

// A file written over a longer time than one call (a map stack written band by band while the
// other stacks of a fit are written too): the temporary sibling `temp()` is what the writer opens;
// Commit() flushes it to disk and renames it over `path()`. Destroyed without Commit() (an error
// mid-way), the temporary is removed, so a failed run leaves no partial output. Move-only.
class PendingFile {
 public:
  // Throws Error naming `path` when its folder does not exist.
  explicit PendingFile(std::filesystem::path path);
  ~PendingFile();
  PendingFile(PendingFile&& other) noexcept;
  PendingFile& operator=(PendingFile&&) = delete;
  PendingFile(const PendingFile&) = delete;
  PendingFile& operator=(const PendingFile&) = delete;

  const std::filesystem::path& path() const { return path_; }
  const std::filesystem::path& temp() const { return temp_; }
  // Flushes what the temporary holds so far to disk in a thread of its own (fdatasync), unless
  // such a flush is still running; returns at once. A writer that writes for long (a map stack
  // band by band) calls it now and then, so that the disk flushes while the program works and
  // Commit's flush finds little left. Why a flush and not only a write-back hint
  // (sync_file_range): on a virtual disk the hint hands the pages to the host's cache, and the
  // final fsync still waited 0.54-0.65 s for a 0.9 GB stack to reach the disk (measured here,
  // ext4 on virtio); with flushes running during the writes it waits 0.01-0.02 s, and no write
  // waited more than 6 ms for them. A failed flush makes Commit fail; a temporary not yet
  // created is skipped.
  void StartWriteback();
  // Throws Error naming path() when flushing or renaming fails (the temporary is then removed).
  void Commit();

 private:
  // Waits for the running flush, if any, and keeps its error.
  void FinishWriteback();

  std::filesystem::path path_;
  std::filesystem::path temp_;
  bool pending_ = true;
  std::future<int> writeback_;  // errno of the running flush, or 0
  int writeback_error_ = 0;     // the first failed flush's errno
};

// WriteFileAtomically for a text or binary blob.
void WriteTextFileAtomically(const std::filesystem::path& path, std::string_view contents);

// WriteTextFileAtomically of the bytes `serialize` returns (a file format's encoder); an Error it
// throws is reported as a fault of `path`.
void WriteSerializedAtomically(const std::filesystem::path& path,
                               const std::function<std::string()>& serialize);

// Reads a whole file; throws Error naming the file if it is missing or unreadable.
std::string ReadTextFile(const std::filesystem::path& path);

}  // namespace photomat
