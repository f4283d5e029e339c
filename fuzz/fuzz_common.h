#pragma once
/// @file
/// What the fuzz targets share: a per-process scratch folder, and the input format of the
/// targets whose reader follows links to other files (a scene's meshes, a project's scene).
///
/// Such an input is a small archive, the main file first:
///
///     [@@file NAME\n]MAIN FILE BYTES
///     \n@@file mesh/liver.msh\nBYTES OF THAT FILE
///     \n@@file other.obj\nBYTES ...
///
/// Names are relative paths inside the scratch folder (letters, digits, '.', '-', '_', at
/// most three levels, no "..": a fuzz input never writes outside it). make-seeds.sh builds
/// such inputs from the repository's scenes and the files they reference.

#include <unistd.h>

#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <string>
#include <string_view>
#include <vector>

namespace hof::fuzz {

/// A folder of this process's own (two targets running side by side never share one),
/// emptied by clear_scratch() before each input and removed at exit.
inline const std::filesystem::path& scratch() {
  static const std::filesystem::path dir = [] {
    const char* tmp = std::getenv("TMPDIR");
    std::filesystem::path d =
        std::filesystem::path(tmp && *tmp ? tmp : "/tmp") / ("hof-fuzz-" + std::to_string(::getpid()));
    std::filesystem::create_directories(d);
    std::atexit([] {
      std::error_code ec;
      std::filesystem::remove_all(scratch(), ec);
    });
    return d;
  }();
  return dir;
}

inline void clear_scratch() {
  std::error_code ec;
  for (const auto& entry : std::filesystem::directory_iterator(scratch(), ec))
    std::filesystem::remove_all(entry.path(), ec);
}

inline void write_file(const std::filesystem::path& path, std::string_view bytes) {
  std::error_code ec;
  std::filesystem::create_directories(path.parent_path(), ec);
  std::ofstream(path, std::ios::binary).write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
}

/// One input written to scratch()/name; returns its path.
inline std::filesystem::path write_input(const std::uint8_t* data, std::size_t size, const std::string& name) {
  clear_scratch();
  const std::filesystem::path path = scratch() / name;
  write_file(path, std::string_view(reinterpret_cast<const char*>(data), size));
  return path;
}

struct ArchiveFile {
  std::string name;  ///< relative path, "" when the archive did not name it
  std::string bytes;
};

inline bool safe_name(std::string_view name) {
  if (name.empty() || name.size() > 64 || name.front() == '/') return false;
  int slashes = 0;
  for (char c : name) {
    const bool ok = (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') || c == '.' ||
                    c == '-' || c == '_' || c == '/';
    if (!ok) return false;
    slashes += c == '/' ? 1 : 0;
  }
  return slashes <= 2 && name.find("..") == std::string_view::npos;
}

/// Splits an archive input (see the file comment); the main file is element 0.
inline std::vector<ArchiveFile> split_archive(std::string_view in) {
  constexpr std::string_view kMarker = "@@file ";
  std::vector<ArchiveFile> files;
  ArchiveFile current;
  if (in.starts_with(kMarker)) {
    const std::size_t eol = in.find('\n');
    current.name = std::string(
        in.substr(kMarker.size(), eol == std::string_view::npos ? std::string_view::npos : eol - kMarker.size()));
    in = eol == std::string_view::npos ? std::string_view{} : in.substr(eol + 1);
  }
  for (;;) {
    const std::size_t at = in.find("\n@@file ");
    current.bytes = std::string(in.substr(0, at));
    files.push_back(std::move(current));
    if (at == std::string_view::npos) break;
    in = in.substr(at + 1 + kMarker.size());
    const std::size_t eol = in.find('\n');
    current = ArchiveFile{std::string(in.substr(0, eol)), {}};
    in = eol == std::string_view::npos ? std::string_view{} : in.substr(eol + 1);
  }
  return files;
}

/// Writes an archive into the emptied scratch folder: the main file as `main_name` (or the
/// archive's own name for it, when `keep_main_name` and it is safe), the others under their
/// names (unsafe names skipped). Returns the main file's path.
inline std::filesystem::path write_archive(const std::uint8_t* data, std::size_t size, const std::string& main_name,
                                           bool keep_main_name = false) {
  clear_scratch();
  const auto files = split_archive(std::string_view(reinterpret_cast<const char*>(data), size));
  std::filesystem::path main = scratch() / main_name;
  if (keep_main_name && safe_name(files.front().name)) main = scratch() / files.front().name;
  for (std::size_t i = 1; i < files.size(); ++i) {
    if (safe_name(files[i].name)) write_file(scratch() / files[i].name, files[i].bytes);
  }
  write_file(main, files.front().bytes);  // last: a linked file of the same name does not replace it
  return main;
}

/// The promise of every reader: a failure is a message naming the file. An error without
/// one is a finding (the target aborts, so that libFuzzer keeps the input).
template <class E>
void check_error(const E& error, const std::filesystem::path& path) {
  const std::string text = error.to_string();
  if (error.message.empty() || (error.file.empty() && text.find(path.filename().string()) == std::string::npos)) {
    std::fprintf(stderr, "error without a message or a file: '%s'\n", text.c_str());
    std::abort();
  }
}

}  // namespace hof::fuzz
