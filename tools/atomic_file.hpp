// Atomic file output: a reader (ParaView, a script, a resumed run) sees either the previous
// complete file or the new complete file, never a half-written one. Data goes to a temporary
// file next to the target (same directory, hence same file system), is flushed to disk, and is
// then renamed over the target; the directory entry is flushed too.
#pragma once
#include <cstddef>
#include <filesystem>
#include <span>
#include <string_view>

namespace turbid::tools {

// `<dir>/<name>.tmp-<pid>` for target `<dir>/<name>`: unique per process, same directory.
std::filesystem::path temp_path_for(const std::filesystem::path& target);

// Flushes `temp` to disk, renames it over `target` and flushes the directory. On failure the
// temporary file is removed and std::runtime_error names both paths.
void commit_temp_file(const std::filesystem::path& temp, const std::filesystem::path& target);

// Writes `bytes` to `target` atomically (temp file, fsync, rename). Creates no directories.
void write_file_atomic(const std::filesystem::path& target, std::span<const std::byte> bytes);
void write_text_atomic(const std::filesystem::path& target, std::string_view text);

// Best-effort fsync of a directory, so that a rename inside it survives a power cut.
void sync_directory(const std::filesystem::path& dir);

}  // namespace turbid::tools
