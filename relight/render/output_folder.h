#pragma once

#include <filesystem>
#include <functional>
#include <string_view>

namespace photomat {

// A folder of outputs (the web viewer, the evaluation report) written whole or not at all, as
// WriteFileAtomically does for one file: `write` fills a fresh temporary sibling folder, which
// then replaces `folder`. `marker` names the file (relative to the folder, JSON with a "format"
// member) that identifies such a folder: an existing `folder` is replaced only when it is empty
// or its marker says `format`, so a mistyped path never deletes unrelated files. Throws Error
// naming `folder`; on failure the temporary folder is removed and `folder` is left as it was.
void WriteFolderAtomically(const std::filesystem::path& folder, std::string_view marker,
                           std::string_view format,
                           const std::function<void(const std::filesystem::path& temp)>& write);

}  // namespace photomat
