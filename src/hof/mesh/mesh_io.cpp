/// @file
/// Format dispatch by file extension, plus the file and mesh checks every reader and
/// writer shares (declared in detail/text_reader.h).

#include "hof/mesh/mesh_io.h"

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <memory>
#include <string>
#include <system_error>

#include "hof/mesh/detail/text_reader.h"

namespace hof::mesh {

namespace detail {

namespace {

struct FileCloser {
  void operator()(std::FILE* f) const { std::fclose(f); }
};
using FilePtr = std::unique_ptr<std::FILE, FileCloser>;

std::string errno_text(int error_number) { return std::generic_category().message(error_number); }

}  // namespace

Expected<std::string> read_whole_file(const std::filesystem::path& path) {
  const std::string file = path.string();
  std::error_code ec;
  const auto status = std::filesystem::status(path, ec);
  if (status.type() == std::filesystem::file_type::not_found) {
    return make_error(ErrorCode::kIo, "cannot open file: no such file", file);
  }
  if (ec) return make_error(ErrorCode::kIo, "cannot open file: " + ec.message(), file);
  if (std::filesystem::is_directory(status)) {
    return make_error(ErrorCode::kIo, "cannot read file: it is a directory", file);
  }
  // A device or pipe (/dev/zero) could be endless: only regular files are read.
  if (!std::filesystem::is_regular_file(status)) {
    return make_error(ErrorCode::kIo, "cannot read file: not a regular file", file);
  }
  const FilePtr f(std::fopen(path.c_str(), "rb"));
  if (!f) return make_error(ErrorCode::kIo, "cannot open file: " + errno_text(errno), file);

  // The size is only a hint (the file may change or be a pipe); read until EOF.
  std::string bytes;
  const auto size_hint = std::filesystem::file_size(path, ec);
  if (!ec) bytes.reserve(static_cast<std::size_t>(size_hint));
  // The first read asks for one byte more than the hint, so that a file of the size stated
  // is read (and its end seen) at once, without zero-filling a whole chunk for a small file.
  constexpr std::size_t kChunk = std::size_t{1} << 20;
  std::size_t chunk = ec ? kChunk : std::min(kChunk, static_cast<std::size_t>(size_hint) + 1);
  std::size_t used = 0;
  while (true) {
    bytes.resize(used + chunk);
    const std::size_t got = std::fread(bytes.data() + used, 1, chunk, f.get());
    used += got;
    if (got < chunk) break;
    chunk = kChunk;
  }
  bytes.resize(used);
  if (std::ferror(f.get()) != 0) {
    return make_error(ErrorCode::kIo, "cannot read file: " + errno_text(errno), file);
  }
  return bytes;
}

Expected<void> write_whole_file(const std::filesystem::path& path, std::string_view bytes) {
  const std::string file = path.string();
  FilePtr f(std::fopen(path.c_str(), "wb"));
  if (!f) return make_error(ErrorCode::kIo, "cannot create file: " + errno_text(errno), file);
  if (std::fwrite(bytes.data(), 1, bytes.size(), f.get()) != bytes.size()) {
    return make_error(ErrorCode::kIo, "cannot write file: " + errno_text(errno), file);
  }
  // fclose flushes; a full disk can show up only here.
  if (std::fclose(f.release()) != 0) {
    return make_error(ErrorCode::kIo, "cannot write file: " + errno_text(errno), file);
  }
  return {};
}

Expected<void> check_mesh_for_write(const Mesh& mesh, const std::filesystem::path& path) {
  const std::string file = path.string();
  const auto fail = [&](const std::string& message) {
    return make_error(ErrorCode::kInvalidArgument, "cannot write mesh: " + message, file);
  };
  const auto n = static_cast<std::int64_t>(mesh.nodes.size());
  if (n == 0) return fail("it has no nodes");
  for (std::size_t i = 0; i < mesh.nodes.size(); ++i) {
    if (!mesh.nodes[i].allFinite()) return fail("node " + std::to_string(i) + " is not finite");
  }
  const auto in_range = [n](NodeIndex v) { return v >= 0 && v < n; };
  for (std::size_t t = 0; t < mesh.tets.size(); ++t) {
    for (const NodeIndex v : mesh.tets[t]) {
      if (!in_range(v))
        return fail("tetrahedron " + std::to_string(t) + " uses node " + std::to_string(v) + " of " +
                    std::to_string(n));
    }
  }
  for (std::size_t t = 0; t < mesh.triangles.size(); ++t) {
    for (const NodeIndex v : mesh.triangles[t]) {
      if (!in_range(v))
        return fail("triangle " + std::to_string(t) + " uses node " + std::to_string(v) + " of " + std::to_string(n));
    }
  }
  if (!mesh.tet_regions.empty() && mesh.tet_regions.size() != mesh.tets.size()) {
    return fail("tet_regions has " + std::to_string(mesh.tet_regions.size()) + " entries for " +
                std::to_string(mesh.tets.size()) + " tetrahedra");
  }
  if (!mesh.triangle_regions.empty() && mesh.triangle_regions.size() != mesh.triangles.size()) {
    return fail("triangle_regions has " + std::to_string(mesh.triangle_regions.size()) + " entries for " +
                std::to_string(mesh.triangles.size()) + " triangles");
  }
  if (!mesh.normals.empty()) {
    if (mesh.normals.size() != mesh.nodes.size()) {
      return fail("normals has " + std::to_string(mesh.normals.size()) + " entries for " + std::to_string(n) +
                  " nodes");
    }
    for (std::size_t i = 0; i < mesh.normals.size(); ++i) {
      if (!mesh.normals[i].allFinite()) return fail("normal " + std::to_string(i) + " is not finite");
    }
  }
  return {};
}

}  // namespace detail

namespace {

enum class Format : std::uint8_t { kMsh, kObj, kStl, kOff, kVtu, kUnknown };

/// The format named by the extension, compared case-insensitively (".MSH" is Gmsh too).
Format format_of(const std::filesystem::path& path) {
  const std::string ext = path.extension().string();
  if (detail::iequals(ext, ".msh")) return Format::kMsh;
  if (detail::iequals(ext, ".obj")) return Format::kObj;
  if (detail::iequals(ext, ".stl")) return Format::kStl;
  if (detail::iequals(ext, ".off")) return Format::kOff;
  if (detail::iequals(ext, ".vtu")) return Format::kVtu;
  return Format::kUnknown;
}

std::unexpected<Error> unknown_extension(const std::filesystem::path& path) {
  std::error_code ec;
  if (std::filesystem::is_directory(path, ec)) {
    return make_error(ErrorCode::kIo, "is a folder, not a mesh file (.msh, .obj, .stl, .off or .vtu)", path.string());
  }

  const std::string ext = path.extension().string();
  return make_error(
      ErrorCode::kUnsupported,
      (ext.empty() ? std::string("file has no extension") : "unknown mesh file extension " + detail::quoted(ext)) +
          "; expected .msh, .obj, .stl, .off or .vtu",
      path.string());
}

}  // namespace

Expected<ReadResult> read_mesh(const std::filesystem::path& path, const ProgressSink& progress) {
  switch (format_of(path)) {
    case Format::kMsh:
      return read_msh(path, progress);
    case Format::kObj:
      return read_obj(path);
    case Format::kStl:
      return read_stl(path);
    case Format::kOff:
      return read_off(path);
    case Format::kVtu:
      return read_vtu(path);
    case Format::kUnknown:
      break;
  }
  // A mistyped path is said to be missing, not to have the wrong extension.
  std::error_code ec;
  if (!std::filesystem::exists(path, ec)) return make_error(ErrorCode::kIo, "no such file", path.string());
  return unknown_extension(path);
}

Expected<void> write_mesh(const Mesh& mesh, const std::filesystem::path& path, MshVersion msh_version) {
  switch (format_of(path)) {
    case Format::kMsh:
      return write_msh(mesh, path, msh_version);
    case Format::kObj:
      return write_obj(mesh, path);
    case Format::kOff:
      return write_off(mesh, path);
    case Format::kVtu:
      return write_vtu(mesh, path);
    case Format::kStl:
      return make_error(ErrorCode::kUnsupported, "writing STL is not supported; write .obj or .off instead",
                        path.string());
    case Format::kUnknown:
      break;
  }
  return unknown_extension(path);
}

}  // namespace hof::mesh
