include(GNUInstallDirs)

# hof_module(NAME SOURCES ... DEPENDS ...): one static library per module of the design,
# `hof_<name>` with alias `hof::<name>` (installed and exported as `HoF::<name>`), include root
# at src/ so headers read <hof/<name>/x.h>. Its public headers are installed with it; those
# under detail/ (and under the PRIVATE_HEADER_DIRS given) stay private.
function(hof_module name)
  cmake_parse_arguments(ARG "" "" "SOURCES;DEPENDS;PRIVATE_DEPENDS;PRIVATE_HEADER_DIRS" ${ARGN})
  add_library(hof_${name} STATIC ${ARG_SOURCES})
  add_library(hof::${name} ALIAS hof_${name})
  target_include_directories(hof_${name} PUBLIC
    $<BUILD_INTERFACE:${PROJECT_SOURCE_DIR}/src>
    $<BUILD_INTERFACE:${PROJECT_BINARY_DIR}/include>
    $<INSTALL_INTERFACE:${CMAKE_INSTALL_INCLUDEDIR}>)
  target_link_libraries(hof_${name} PUBLIC ${ARG_DEPENDS} PRIVATE $<BUILD_INTERFACE:hof_warnings> ${ARG_PRIVATE_DEPENDS})
  set_target_properties(hof_${name} PROPERTIES EXPORT_NAME ${name})
  install(TARGETS hof_${name} EXPORT HoFTargets ARCHIVE DESTINATION ${CMAKE_INSTALL_LIBDIR} COMPONENT development)
  set(excluded PATTERN "detail" EXCLUDE)
  foreach(dir IN LISTS ARG_PRIVATE_HEADER_DIRS)
    list(APPEND excluded PATTERN "${dir}" EXCLUDE)
  endforeach()
  install(DIRECTORY ${CMAKE_CURRENT_SOURCE_DIR}/ DESTINATION ${CMAKE_INSTALL_INCLUDEDIR}/hof/${name} COMPONENT development
    FILES_MATCHING PATTERN "*.h" ${excluded})
  set_property(GLOBAL APPEND PROPERTY HOF_MODULES ${name})
endfunction()

# hof_test(NAME SOURCES ... DEPENDS ...): a GoogleTest executable registered with CTest.
# HOF_ANCHORS points at ../shared/anchors (third-party inputs read in place, never copied).
function(hof_test name)
  cmake_parse_arguments(ARG "" "" "SOURCES;DEPENDS" ${ARGN})
  add_executable(${name} ${ARG_SOURCES})
  target_link_libraries(${name} PRIVATE ${ARG_DEPENDS} GTest::gtest_main GTest::gmock hof_warnings)
  target_include_directories(${name} PRIVATE ${PROJECT_SOURCE_DIR}/tests)
  target_compile_definitions(${name} PRIVATE
    HOF_ANCHORS_DIR="${HOF_ANCHORS_DIR}" HOF_SOURCE_DIR="${PROJECT_SOURCE_DIR}")
  gtest_discover_tests(${name} DISCOVERY_TIMEOUT 60 PROPERTIES TIMEOUT 600)
endfunction()
