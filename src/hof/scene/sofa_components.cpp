#include "hof/scene/sofa_components.h"

#include <algorithm>
#include <array>

#include "hof/core/text.h"

// The data names of the components HoF reads (names only: facts about SOFA's scene format), the
// initData()/addAlias() names of each class and its base classes in SOFA's repository
// (sofa-framework/sofa v25.06), and the closest-name search. The component names themselves
// are in sofa_component_names.cpp.

namespace hof::scene::detail {
namespace {


struct DataNames {
  std::string_view type;
  std::span<const std::string_view> names;
};

constexpr std::string_view kDataDiagonalMass[] = {
    "bbox", "componentState", "computeMassOnRest", "fileMass", "filename", "geometryState", "listening",
    "massDensity", "mechanicalStates", "mstate", "name", "printLog", "rayleighMass", "rayleighStiffness",
    "separateGravity", "showAxisSizeFactor", "showGravityCenter", "tags", "topology", "totalMass",
    "vertexMass",
};
constexpr std::string_view kDataEulerImplicitSolver[] = {
    "bbox", "componentState", "computeResidual", "firstOrder", "linearSolver", "listening", "name",
    "printLog", "rayleighMass", "rayleighStiffness", "residual", "solveConstraint", "tags",
    "threadSafeVisitor", "trapezoidalScheme", "vdamping",
};
constexpr std::string_view kDataFastTetrahedralCorotationalForceField[] = {
    "bbox", "componentState", "drawColor1", "drawColor2", "drawColor3", "drawColor4", "drawing", "edgeInfo",
    "listening", "mechanicalStates", "method", "mstate", "name", "pointInfo", "poissonRatio", "printLog",
    "rayleighStiffness", "tags", "tetrahedronInfo", "topology", "youngModulus",
};
constexpr std::string_view kDataHexahedronFEMForceField[] = {
    "bbox", "componentState", "drawPercentageOffset", "drawing", "gatherBsize", "gatherPt", "initialPoints",
    "listening", "mechanicalStates", "method", "mstate", "name", "poissonRatio", "printLog",
    "rayleighStiffness", "stiffnessMatrices", "tags", "topology", "updateStiffnessMatrix", "youngModulus",
};
constexpr std::string_view kDataMechanicalObject[] = {
    "bbox", "componentState", "constraint", "derivX", "drawMode", "dx", "dx2", "dy", "dy2", "dz", "dz2",
    "externalForce", "force", "free_position", "free_velocity", "listening", "mappingJacobian", "name",
    "position", "printLog", "reserve", "reset_position", "reset_velocity", "restScale", "rest_position",
    "rotation", "rotation2", "rx", "rx2", "ry", "ry2", "rz", "rz2", "scale", "scale3d", "showColor",
    "showIndices", "showIndicesScale", "showObject", "showObjectScale", "showVectors", "showVectorsScale",
    "size", "sx", "sy", "sz", "tags", "topology", "translation", "translation2", "useTopology", "velocity",
};
constexpr std::string_view kDataMeshMatrixMass[] = {
    "bbox", "componentState", "computeMassOnRest", "edgeMass", "geometryState", "graph", "listening",
    "lumping", "massDensity", "mechanicalStates", "mstate", "name", "printLog", "printMass", "rayleighMass",
    "rayleighStiffness", "separateGravity", "showAxisSizeFactor", "showGravityCenter", "tags", "topology",
    "totalMass", "vertexMass",
};
constexpr std::string_view kDataMeshSpringForceField[] = {
    "bbox", "componentState", "cubesDamping", "cubesStiffness", "damping", "drawMaxElongationRange",
    "drawMinElongationRange", "drawMode", "drawSpringSize", "elongationOnly", "enabled", "fileSprings",
    "indices1", "indices2", "length", "lengths", "linesDamping", "linesStiffness", "listening", "localRange",
    "mechanicalStates", "name", "noCompression", "object1", "object2", "printLog", "quadsDamping",
    "quadsStiffness", "rayleighStiffness", "showArrowSize", "spring", "springsIndices1", "springsIndices2",
    "stiffness", "stiffnessRule", "tags", "tangent", "tetrahedraDamping", "tetrahedraStiffness", "tetrasDamping",
    "tetrasStiffness", "topology", "trianglesDamping", "trianglesStiffness",
    // stiffnessRule and tangent: HoF extensions (HoF's own spring rule), not SOFA data.
};
constexpr std::string_view kDataSpringForceField[] = {
    "bbox", "componentState", "damping", "drawMode", "elongationOnly", "enabled", "fileSprings", "indices1",
    "indices2", "length", "lengths", "listening", "mechanicalStates", "name", "object1", "object2",
    "printLog", "rayleighStiffness", "showArrowSize", "spring", "springsIndices1", "springsIndices2",
    "stiffness", "tags",
};
constexpr std::string_view kDataTetrahedralCorotationalFEMForceField[] = {
    "assembling", "bbox", "componentState", "computeGlobalMatrix", "drawColor1", "drawColor2", "drawColor3",
    "drawColor4", "drawing", "listening", "localStiffnessFactor", "mechanicalStates", "method", "mstate",
    "name", "poissonRatio", "printLog", "rayleighStiffness", "tags", "tetrahedronInfo", "topology",
    "updateStiffnessMatrix", "youngModulus",
};
constexpr std::string_view kDataTetrahedronFEMForceField[] = {
    "assembling", "bbox", "componentState", "computeGlobalMatrix", "computeVonMisesStress",
    "drawHeterogeneousTetra", "gatherBsize", "gatherPt", "initialPoints", "listening", "localStiffnessFactor",
    "mechanicalStates", "method", "mstate", "name", "plasticCreep", "plasticMaxThreshold",
    "plasticYieldThreshold", "poissonRatio", "printLog", "rayleighStiffness", "showElementGapScale",
    "showStressAlpha", "showStressColorMap", "showVonMisesStressPerElement", "showVonMisesStressPerNode",
    "showVonMisesStressPerNodeColorMap", "tags", "topology", "updateStiffness", "updateStiffnessMatrix",
    "vonMisesPerElement", "vonMisesPerNode", "vonMisesStressColors", "youngModulus",
};
constexpr std::string_view kDataTriangleFEMForceField[] = {
    "bbox", "componentState", "initialPoints", "listening", "mechanicalStates", "method", "mstate", "name",
    "planeStrain", "poissonRatio", "printLog", "rayleighStiffness", "tags", "thickness", "topology",
    "youngModulus",
};
constexpr std::string_view kDataTriangularFEMForceField[] = {
    "bbox", "componentState", "computePrincipalStress", "criteriaValue", "hosfordExponant",
    "initialTransformation", "listening", "mechanicalStates", "method", "mstate", "name", "poissonRatio",
    "printLog", "rayleighStiffness", "rotatedInitialElements", "showFracturableTriangles", "showStressValue",
    "showStressVector", "tags", "topology", "triangleInfo", "vertexInfo", "youngModulus",
};
constexpr std::string_view kDataUniformMass[] = {
    "bbox", "componentState", "compute_mapping_inertia", "filename", "indices", "listening", "localRange",
    "mechanicalStates", "mstate", "name", "preserveTotalMass", "printLog", "rayleighMass",
    "rayleighStiffness", "separateGravity", "showAxisSizeFactor", "showGravityCenter",
    "showInitialCenterOfGravity", "showX0", "tags", "topology", "totalMass", "vertexMass",
};

constexpr DataNames kData[] = {
    {"DiagonalMass", kDataDiagonalMass},
    {"EulerImplicitSolver", kDataEulerImplicitSolver},
    {"FastTetrahedralCorotationalForceField", kDataFastTetrahedralCorotationalForceField},
    {"HexahedronFEMForceField", kDataHexahedronFEMForceField},
    {"MechanicalObject", kDataMechanicalObject},
    {"MeshMatrixMass", kDataMeshMatrixMass},
    {"MeshSpringForceField", kDataMeshSpringForceField},
    {"SpringForceField", kDataSpringForceField},
    {"TetrahedralCorotationalFEMForceField", kDataTetrahedralCorotationalFEMForceField},
    {"TetrahedronFEMForceField", kDataTetrahedronFEMForceField},
    {"TriangleFEMForceField", kDataTriangleFEMForceField},
    {"TriangularFEMForceField", kDataTriangularFEMForceField},
    {"UniformMass", kDataUniformMass},
};

}  // namespace

bool is_known_sofa_component(std::string_view type) {
  return std::ranges::binary_search(known_sofa_components(), type);
}

std::span<const std::string_view> sofa_data_names(std::string_view type) {
  for (const DataNames& d : kData)
    if (d.type == type) return d.names;
  return {};
}

std::vector<std::string> closest_names(std::string_view name, std::span<const std::string_view> candidates, std::size_t count) {
  const std::size_t limit = std::max<std::size_t>(2, name.size() / 3);
  std::vector<std::pair<std::size_t, std::string_view>> scored;
  for (std::string_view c : candidates) {
    const std::size_t d = edit_distance(name, c);
    if (d <= limit) scored.emplace_back(d, c);
  }
  std::ranges::sort(scored);
  std::vector<std::string> out;
  for (std::size_t i = 0; i < scored.size() && out.size() < count; ++i) out.emplace_back(scored[i].second);
  return out;
}

}  // namespace hof::scene::detail
