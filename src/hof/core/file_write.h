#pragma once
/// @file
/// Writing users' files so that a crash, a full disk or a vanished folder never leaves one
/// half-written: the bytes go to a temporary file in the same folder, are flushed to the disk,
/// and only then replace the target (rename(2) is atomic within a file system). Either the
/// old file or the whole new one is there, never a mix.

#include <filesystem>
#include <string_view>

#include "hof/core/error.h"

namespace hof {

/// Writes `content` to `path` atomically (temporary file, fsync, rename, fsync of the folder).
/// The temporary file is removed on any failure. An existing file keeps its permissions.
/// Errors (kIo) name the file and the system's reason ("No space left on device").
[[nodiscard]] Expected<void> write_file_atomically(const std::filesystem::path& path, std::string_view content);

}  // namespace hof
