# Runs the mesh verbs one after the other as a user would and checks what each produced.
file(REMOVE_RECURSE ${WORK})
file(MAKE_DIRECTORY ${WORK})

function(run)
  execute_process(COMMAND ${ARGN} RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
  if(NOT rc EQUAL 0)
    message(FATAL_ERROR "failed (${rc}): ${ARGN}\n${out}\n${err}")
  endif()
  set(LAST_OUTPUT "${out}" PARENT_SCOPE)
endfunction()

run(${HOF} mesh generate liver --resolution simple -o ${WORK}/liver-simple.msh --quiet)
foreach(f liver-simple.msh liver-simple.obj)
  if(NOT EXISTS ${WORK}/${f})
    message(FATAL_ERROR "generate did not write ${f}")
  endif()
endforeach()

run(${HOF} mesh info --json ${WORK}/liver-simple.msh)
string(JSON problems LENGTH "${LAST_OUTPUT}" problems)
string(JSON inverted GET "${LAST_OUTPUT}" quality inverted)
string(JSON outward GET "${LAST_OUTPUT}" surface outward)
if(NOT problems EQUAL 0 OR NOT inverted EQUAL 0 OR NOT outward)
  message(FATAL_ERROR "generated liver has problems:\n${LAST_OUTPUT}")
endif()

run(${HOF} mesh convert ${WORK}/liver-simple.msh ${WORK}/liver-simple.vtu --quiet)
run(${HOF} mesh convert ${WORK}/liver-simple.msh ${WORK}/liver-v2.msh --msh-version 2 --quiet)
file(STRINGS ${WORK}/liver-v2.msh header LIMIT_COUNT 2)
list(GET header 1 version_line)
if(NOT version_line MATCHES "^2.2 0 8")
  message(FATAL_ERROR "expected a v2.2 ASCII file, got '${version_line}'")
endif()

# The surface written beside the volume meshes again into a closed volume.
run(${HOF} mesh tetrahedralize ${WORK}/liver-simple.obj -o ${WORK}/remeshed.msh --max-volume 1e-6 --quiet)
run(${HOF} mesh info --json ${WORK}/remeshed.msh)
string(JSON tets GET "${LAST_OUTPUT}" tetrahedra)
if(tets LESS 1000)
  message(FATAL_ERROR "--max-volume 1e-6 should give over 1000 tets, got ${tets}")
endif()

# An open surface is refused with a message naming the file.
file(WRITE ${WORK}/open.obj "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nf 1 3 2\nf 1 2 4\nf 1 4 3\n")
execute_process(COMMAND ${HOF} mesh tetrahedralize ${WORK}/open.obj -o ${WORK}/open.msh --quiet
                RESULT_VARIABLE rc ERROR_VARIABLE err)
if(rc EQUAL 0 OR NOT err MATCHES "open.obj: the surface is not closed")
  message(FATAL_ERROR "open surface not reported clearly (rc=${rc}): ${err}")
endif()
