#pragma once
/// @file
/// The `hof mesh ...` verbs, separated from command-line parsing so they can be called from
/// tests and from other front ends. Each returns the process exit status (0 = success) and
/// prints errors as "hof: FILE:LINE: message" on stderr.

#include <filesystem>
#include <optional>
#include <string>

namespace hof::app {

struct MeshInfoOptions {
  std::filesystem::path file;
  /// The unit of the file's numbers (m, cm, mm); empty: not stated, lengths as the numbers.
  std::string unit;
  bool json{false};
  bool quiet{false};
};

struct MeshGenerateOptions {
  std::string shape{"liver"};
  std::string resolution{"medium"};
  std::filesystem::path output;
  int msh_version{4};  ///< 2 or 4 (for .msh output)
  bool quiet{false};
};

struct MeshTetrahedralizeOptions {
  std::filesystem::path surface;
  std::filesystem::path output;
  double max_volume_m3{0.0};
  double quality{1.414};  ///< radius-edge ratio bound; 0 = off
  double min_dihedral_deg{0.0};
  bool preserve_surface{false};
  int msh_version{4};
  bool quiet{false};
};

struct MeshConvertOptions {
  std::filesystem::path input;
  std::filesystem::path output;
  int msh_version{4};
  bool quiet{false};
};

int run_mesh_info(const MeshInfoOptions& options);
int run_mesh_generate(const MeshGenerateOptions& options);
int run_mesh_tetrahedralize(const MeshTetrahedralizeOptions& options);
int run_mesh_convert(const MeshConvertOptions& options);

}  // namespace hof::app
