#pragma once
/// @file
/// Gmsh's element types, for the .msh reader (io_msh.cpp): each type number's node count
/// (Gmsh's GmshDefines.h, MSH_*) and what the reader does with it (linear tetrahedra and
/// triangles kept, points and lines counted, other known types counted with a warning, an
/// unknown number an error).

#include <array>
#include <cstdint>

namespace hof::mesh::detail {

/// Node count of a type whose layout has no fixed node count (polygons, sub-elements).
constexpr std::uint16_t kVariable = 0xffff;

/// Node count per Gmsh element type number (Gmsh's GmshDefines.h, MSH_*); 0 = no such type.
constexpr std::array<std::uint16_t, 141> kGmshNodeCount = {
    0,                                                                          // 0: none
    2,   3,   4,         4,         8,         6,         5,   3,    6,   9,    // 1-10
    10,  27,  18,        14,        1,         8,         20,  15,   13,  9,    // 11-20
    10,  12,  15,        15,        21,        4,         5,   6,    20,  35,   // 21-30
    56,  22,  28,        kVariable, kVariable, 16,        25,  36,   12,  16,   // 31-40
    20,  28,  36,        45,        55,        66,        49,  64,   81,  100,  // 41-50
    121, 18,  21,        24,        27,        30,        24,  28,   32,  36,   // 51-60
    40,  7,   8,         9,         10,        11,        0,   0,    0,   0,    // 61-70
    84,  120, 165,       220,       286,       0,         0,   0,    34,  40,   // 71-80
    46,  52,  58,        1,         1,         1,         1,   1,    1,   40,   // 81-90
    75,  64,  125,       216,       343,       512,       729, 1000, 32,  44,   // 91-100
    56,  68,  80,        92,        104,       126,       196, 288,  405, 550,  // 101-110
    24,  33,  42,        51,        60,        69,        78,  30,   55,  91,   // 111-120
    140, 204, 285,       385,       21,        29,        37,  45,   53,  61,   // 121-130
    69,  1,   kVariable, kVariable, kVariable, kVariable, 16,  4,    5,   4,    // 131-140
};
static_assert(kGmshNodeCount[4] == 4 && kGmshNodeCount[15] == 1 && kGmshNodeCount[71] == 84 &&
              kGmshNodeCount[79] == 34 && kGmshNodeCount[92] == 64 && kGmshNodeCount[132] == 1 &&
              kGmshNodeCount[140] == 4);

/// What the reader does with an element type.
enum class ElementKind : std::uint8_t { kUnknown, kUnsupported, kPoint, kLine, kTriangle, kTet, kOther };

struct ElementInfo {
  int nodes{0};
  ElementKind kind{ElementKind::kUnknown};
};

inline ElementInfo element_info(std::int64_t type) {
  if (type < 0 || type >= static_cast<std::int64_t>(kGmshNodeCount.size())) return {};
  const std::uint16_t nodes = kGmshNodeCount[static_cast<std::size_t>(type)];
  if (nodes == 0) return {};
  if (nodes == kVariable) return {0, ElementKind::kUnsupported};
  switch (type) {
    case 2:
      return {3, ElementKind::kTriangle};
    case 4:
      return {4, ElementKind::kTet};
    case 15:
      return {1, ElementKind::kPoint};
    case 1:
    case 8:
    case 26:
    case 27:
    case 28:
    case 62:
    case 63:
    case 64:
    case 65:
    case 66:
      return {nodes, ElementKind::kLine};
    default:
      return {nodes, ElementKind::kOther};
  }
}

/// Largest element (MSH_HEX_1000): bounds the scratch buffer of node tags.
constexpr int kMaxElementNodes = 1000;

}  // namespace hof::mesh::detail
