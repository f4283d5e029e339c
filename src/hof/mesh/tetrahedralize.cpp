#include "hof/mesh/tetrahedralize.h"

#include <sys/wait.h>
#include <tetgen.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <vector>

#include <fmt/format.h>
#include <cmath>
#include <cstdio>

#include "hof/mesh/boundary.h"
#include "hof/mesh/surface_check.h"
#include "hof/mesh/tet_geometry.h"

namespace hof::mesh {

namespace {

// TetGen 1.5.0 reports failures by throwing an int from deep inside, and while the exception
// unwinds its own mesh destructor can crash (seen with a self-intersecting surface). It also
// prints its diagnosis to stdout. So TetGen runs in a forked child process: the child's stdout
// goes to a temporary file (the diagnosis for the error message), the result comes back
// through a pipe, and a crash in the child becomes an error here instead of taking HoF down.

struct ChildResult {
  std::vector<double> points;  // 3 per point
  std::vector<int> tets;       // 4 per tet
  int tetgen_code{0};          // the int TetGen threw, 0 when it succeeded
};

bool write_all(int fd, const void* data, std::size_t size) {
  const char* p = static_cast<const char*>(data);
  while (size > 0) {
    const ssize_t n = ::write(fd, p, size);
    if (n < 0) {
      if (errno == EINTR) continue;
      return false;
    }
    p += n;
    size -= static_cast<std::size_t>(n);
  }
  return true;
}

// Runs in the child: mesh, then send [code][npoints][ntets][points][tets] and exit.
[[noreturn]] void run_tetgen_child(tetgenio& in, std::string switches, int result_fd, int text_fd) {
  dup2(text_fd, STDOUT_FILENO);
  setvbuf(stdout, nullptr, _IONBF, 0);  // keep TetGen's words even if it crashes next
  tetgenio out;
  std::int32_t code = 0;
  try {
    ::tetrahedralize(switches.data(), &in, &out);
  } catch (int thrown) {
    code = thrown == 0 ? -1 : thrown;
  } catch (...) {
    code = -1;
  }
  const std::int64_t npoints = code == 0 ? out.numberofpoints : 0;
  const std::int64_t ntets = code == 0 && out.numberofcorners == 4 ? out.numberoftetrahedra : 0;
  bool ok = write_all(result_fd, &code, sizeof code) && write_all(result_fd, &npoints, sizeof npoints) &&
            write_all(result_fd, &ntets, sizeof ntets);
  if (ok && npoints > 0)
    ok = write_all(result_fd, out.pointlist, sizeof(double) * 3 * static_cast<std::size_t>(npoints));
  if (ok && ntets > 0)
    ok = write_all(result_fd, out.tetrahedronlist, sizeof(int) * 4 * static_cast<std::size_t>(ntets));
  ::_exit(ok ? 0 : 3);
}

std::string read_text(std::FILE* file) {
  std::string text;
  std::rewind(file);
  char buffer[4096];
  std::size_t n = 0;
  while ((n = std::fread(buffer, 1, sizeof buffer, file)) > 0 && text.size() < 65536) text.append(buffer, n);
  return text;
}

std::string tetgen_diagnosis(int code, const std::string& printed) {
  // TetGen's own lines (advice on switches dropped) follow our reading of its exit code.
  std::string lines;
  std::size_t start = 0;
  while (start < printed.size()) {
    std::size_t end = printed.find('\n', start);
    if (end == std::string::npos) end = printed.size();
    std::string line = printed.substr(start, end - start);
    start = end + 1;
    const std::size_t first = line.find_first_not_of(" \t\r");
    if (first == std::string::npos || line.find("switch") != std::string::npos) continue;
    if (lines.size() < 400) lines += (lines.empty() ? "" : " ") + line.substr(first);
  }
  std::string meaning;
  if (printed.find("elf-intersection") != std::string::npos || printed.find("intersect") != std::string::npos) {
    code = 3;
  }
  switch (code) {
    case 1:
      meaning = "out of memory";
      break;
    case 2:
      meaning = "internal error in TetGen";
      break;
    case 3:
      meaning = "the surface intersects itself";
      break;
    case 4:
      meaning = "the surface has a very small feature (nearly coincident vertices or faces)";
      break;
    case 5:
      meaning = "two facets of the surface are very close to each other";
      break;
    case 10:
      meaning = "TetGen rejected the input";
      break;
    default:
      meaning = code > 0 ? fmt::format("TetGen failed with code {}", code) : "TetGen failed";
      break;
  }
  return lines.empty() ? meaning : meaning + " (TetGen: " + lines + ")";
}

Expected<ChildResult> run_tetgen_isolated(tetgenio& in, const std::string& switches, const std::string& source_name) {
  int fds[2];
  std::FILE* text = std::tmpfile();
  if (text == nullptr || ::pipe(fds) != 0) {
    if (text != nullptr) std::fclose(text);
    return make_error(ErrorCode::kMeshing, fmt::format("{}: cannot start the mesher (pipe)", source_name));
  }
  std::fflush(nullptr);
  const pid_t pid = ::fork();
  if (pid < 0) {
    ::close(fds[0]);
    ::close(fds[1]);
    std::fclose(text);
    return make_error(ErrorCode::kMeshing, fmt::format("{}: cannot start the mesher (fork)", source_name));
  }
  if (pid == 0) {
    ::close(fds[0]);
    run_tetgen_child(in, switches, fds[1], fileno(text));
  }
  ::close(fds[1]);
  std::vector<char> bytes;
  char buffer[1 << 16];
  for (;;) {
    const ssize_t n = ::read(fds[0], buffer, sizeof buffer);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) break;
    bytes.insert(bytes.end(), buffer, buffer + n);
  }
  ::close(fds[0]);
  int status = 0;
  while (::waitpid(pid, &status, 0) < 0 && errno == EINTR) {
  }
  const std::string printed = read_text(text);
  std::fclose(text);

  // -d mode lists the intersecting facets ("Facet #3 intersects facet #17 ...").
  if (const std::size_t at = printed.find("Facet #");
      at != std::string::npos && printed.find("intersects facet", at) != std::string::npos) {
    std::size_t pairs = 0;
    for (std::size_t i = at; (i = printed.find("intersects facet", i)) != std::string::npos; ++i) ++pairs;
    const std::string first = printed.substr(at, printed.find('\n', at) - at);
    return make_error(ErrorCode::kMeshing,
                      fmt::format("{}: meshing failed: the surface intersects itself: {} pairs of "
                                  "triangles cross (first: {}; facet numbers are 0-based triangle indices)",
                                  source_name, pairs, first));
  }

  ChildResult result;
  constexpr std::size_t kHeader = sizeof(std::int32_t) + 2 * sizeof(std::int64_t);
  if (bytes.size() >= kHeader) {
    std::int32_t code = 0;
    std::int64_t npoints = 0, ntets = 0;
    std::memcpy(&code, bytes.data(), sizeof code);
    std::memcpy(&npoints, bytes.data() + 4, sizeof npoints);
    std::memcpy(&ntets, bytes.data() + 12, sizeof ntets);
    const std::size_t expected = kHeader + sizeof(double) * 3 * static_cast<std::size_t>(npoints) +
                                 sizeof(int) * 4 * static_cast<std::size_t>(ntets);
    if (code != 0) {
      return make_error(ErrorCode::kMeshing,
                        fmt::format("{}: meshing failed: {}", source_name, tetgen_diagnosis(code, printed)));
    }
    if (npoints >= 0 && ntets >= 0 && bytes.size() == expected && WIFEXITED(status) && WEXITSTATUS(status) == 0) {
      result.points.resize(3 * static_cast<std::size_t>(npoints));
      result.tets.resize(4 * static_cast<std::size_t>(ntets));
      std::memcpy(result.points.data(), bytes.data() + kHeader, sizeof(double) * result.points.size());
      std::memcpy(result.tets.data(), bytes.data() + kHeader + sizeof(double) * result.points.size(),
                  sizeof(int) * result.tets.size());
      return result;
    }
  }
  const int code = WIFSIGNALED(status) ? 0 : (WIFEXITED(status) ? WEXITSTATUS(status) : 0);
  return make_error(ErrorCode::kMeshing,
                    fmt::format("{}: meshing failed: {}{}", source_name, tetgen_diagnosis(code, printed),
                                WIFSIGNALED(status) ? " [TetGen crashed; HoF was not affected]" : ""));
}

}  // namespace

Expected<Mesh> tetrahedralize(const TriMesh& surface, const TetrahedralizeOptions& options,
                              const std::string& source_name) {
  if (!(options.max_volume_m3 >= 0.0) || !std::isfinite(options.max_volume_m3)) {
    return make_error(ErrorCode::kInvalidArgument,
                      fmt::format("max volume must be a finite value >= 0, got {}", options.max_volume_m3));
  }
  if (options.radius_edge_ratio != 0.0 && !(options.radius_edge_ratio >= 1.0 && options.radius_edge_ratio < 100.0)) {
    return make_error(ErrorCode::kInvalidArgument,
                      fmt::format("quality (radius-edge ratio bound) must be 0 (off) or in [1, 100), got {} "
                                  "(TetGen does not terminate below 1)",
                                  options.radius_edge_ratio));
  }
  if (!(options.min_dihedral_deg >= 0.0 && options.min_dihedral_deg < 30.0)) {
    return make_error(
        ErrorCode::kInvalidArgument,
        fmt::format("minimum dihedral angle must be in [0, 30) degrees, got {}", options.min_dihedral_deg));
  }
  for (std::size_t i = 0; i < surface.vertices.size(); ++i) {
    if (!surface.vertices[i].allFinite()) {
      return make_error(ErrorCode::kMeshing, fmt::format("{}: vertex {} has a non-finite coordinate", source_name, i));
    }
  }
  for (std::size_t t = 0; t < surface.triangles.size(); ++t) {
    for (NodeIndex v : surface.triangles[t]) {
      if (v < 0 || static_cast<std::size_t>(v) >= surface.vertices.size()) {
        return make_error(ErrorCode::kMeshing, fmt::format("{}: triangle {} refers to vertex {} of {}", source_name, t,
                                                           v, surface.vertices.size()));
      }
    }
  }

  // TetGen needs a watertight boundary; say precisely what is wrong before it does.
  const SurfaceCheck check = check_surface(surface);
  if (!check.closed_manifold()) {
    std::string where;
    if (check.first_bad_edge) {
      where = fmt::format(" (first at the edge between vertices {} and {})", (*check.first_bad_edge)[0],
                          (*check.first_bad_edge)[1]);
    }
    if (check.triangles == 0) {
      return make_error(ErrorCode::kMeshing, fmt::format("{}: the surface has no triangles", source_name));
    }
    if (check.boundary_edges > 0) {
      return make_error(ErrorCode::kMeshing, fmt::format("{}: the surface is not closed: {} edges belong to only one "
                                                         "triangle{}",
                                                         source_name, check.boundary_edges, where));
    }
    if (check.degenerate_triangles > 0) {
      return make_error(ErrorCode::kMeshing, fmt::format("{}: {} degenerate triangles (zero area or a repeated vertex)",
                                                         source_name, check.degenerate_triangles));
    }
    return make_error(ErrorCode::kMeshing,
                      fmt::format("{}: the surface is not a 2-manifold: {} edges shared by 3+ "
                                  "triangles, {} pinched vertices, {} inconsistently oriented edges{}",
                                  source_name, check.non_manifold_edges, check.non_manifold_vertices,
                                  check.misoriented_edges, where));
  }

  tetgenio in;
  in.firstnumber = 0;
  in.numberofpoints = static_cast<int>(surface.vertices.size());
  in.pointlist = new REAL[surface.vertices.size() * 3];
  for (std::size_t i = 0; i < surface.vertices.size(); ++i) {
    for (int k = 0; k < 3; ++k) in.pointlist[3 * i + k] = surface.vertices[i][k];
  }
  in.numberoffacets = static_cast<int>(surface.triangles.size());
  in.facetlist = new tetgenio::facet[surface.triangles.size()];
  for (std::size_t t = 0; t < surface.triangles.size(); ++t) {
    tetgenio::facet& f = in.facetlist[t];
    tetgenio::init(&f);
    f.numberofpolygons = 1;
    f.polygonlist = new tetgenio::polygon[1];
    tetgenio::init(&f.polygonlist[0]);
    f.polygonlist[0].numberofvertices = 3;
    f.polygonlist[0].vertexlist = new int[3];
    for (int k = 0; k < 3; ++k) f.polygonlist[0].vertexlist[k] = surface.triangles[t][k];
  }

  // p: piecewise linear complex; z: number from zero; Q: quiet; q: quality; a: volume bound.
  std::string switches = "pz";
  if (options.radius_edge_ratio > 0.0) {
    switches += fmt::format("q{:.6g}", options.radius_edge_ratio);
    if (options.min_dihedral_deg > 0.0) switches += fmt::format("/{:.6g}", options.min_dihedral_deg);
  }
  if (options.max_volume_m3 > 0.0) switches += fmt::format("a{:.9g}", options.max_volume_m3);
  if (options.preserve_surface) switches += "Y";

  auto result = run_tetgen_isolated(in, switches, source_name);
  if (!result) {
    // A failed run may have crashed before saying why. TetGen's -d mode only looks for
    // intersecting facets; when it finds any, that is the diagnosis the user needs.
    auto detection = run_tetgen_isolated(in, "pzd", source_name);
    if (!detection && detection.error().message.find("intersects itself") != std::string::npos) {
      return std::unexpected(detection.error());
    }
    return std::unexpected(result.error());
  }
  const std::size_t npoints = result->points.size() / 3;
  const std::size_t ntets = result->tets.size() / 4;
  if (ntets == 0) {
    return make_error(ErrorCode::kMeshing, fmt::format("{}: TetGen produced no linear tetrahedra", source_name));
  }

  Mesh mesh;
  mesh.nodes.resize(npoints);
  const std::vector<double>& p = result->points;
  for (std::size_t i = 0; i < npoints; ++i) mesh.nodes[i] = Vec3(p[3 * i], p[3 * i + 1], p[3 * i + 2]);
  mesh.tets.resize(ntets);
  const std::vector<int>& q = result->tets;
  for (std::size_t t = 0; t < ntets; ++t) {
    Tet tet = {q[4 * t], q[4 * t + 1], q[4 * t + 2], q[4 * t + 3]};
    for (NodeIndex n : tet) {
      if (n < 0 || static_cast<std::size_t>(n) >= npoints) {
        return make_error(ErrorCode::kMeshing, fmt::format("{}: TetGen returned an invalid tetrahedron", source_name));
      }
    }
    const auto c = tet_corners(mesh.nodes, tet);
    // HoF's convention is positive orientation; TetGen's is the opposite.
    if (tet_signed_volume(c[0], c[1], c[2], c[3]) < 0.0) std::swap(tet[2], tet[3]);
    mesh.tets[t] = tet;
  }
  mesh.triangles = extract_boundary(mesh.nodes, mesh.tets).volume_triangles;
  return mesh;
}

}  // namespace hof::mesh
