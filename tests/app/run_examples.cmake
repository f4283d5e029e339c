# Runs hof run as a user would, on every bundled example, and checks the report.
file(REMOVE_RECURSE ${WORK})
file(MAKE_DIRECTORY ${WORK})
file(GLOB projects ${SOURCE}/examples/*.hof)
foreach(project ${projects})
  get_filename_component(name ${project} NAME_WE)
  execute_process(COMMAND ${HOF} run ${project} --deterministic --seconds 1.5 --quiet --out ${WORK}/${name}
                  RESULT_VARIABLE rc ERROR_VARIABLE err)
  if(NOT rc EQUAL 0)
    message(FATAL_ERROR "hof run ${name} failed (${rc}): ${err}")
  endif()
  file(READ ${WORK}/${name}/summary.json summary)
  string(JSON fall GET "${summary}" fall_through_events)
  string(JSON diverged GET "${summary}" diverged)
  string(JSON ticks GET "${summary}" haptic ticks)
  if(NOT fall EQUAL 0 OR diverged OR NOT ticks EQUAL 1500)
    message(FATAL_ERROR "${name}: fall-through ${fall}, diverged ${diverged}, ticks ${ticks}")
  endif()
  foreach(f telemetry.csv force_over_time.png force_vs_indentation.svg haptic_period_histogram.png)
    if(NOT EXISTS ${WORK}/${name}/${f})
      message(FATAL_ERROR "${name}: no ${f} in the report")
    endif()
  endforeach()
endforeach()

# Deterministic runs give identical telemetry.
execute_process(COMMAND ${HOF} run ${SOURCE}/examples/liver-palpation-simple.hof --deterministic --seconds 1.5 --quiet --out ${WORK}/again)
file(SHA256 ${WORK}/liver-palpation-simple/telemetry.csv first)
file(SHA256 ${WORK}/again/telemetry.csv second)
if(NOT first STREQUAL second)
  message(FATAL_ERROR "two deterministic runs wrote different telemetry")
endif()

# A missing mesh is an error naming the file; a broken project names its line.
file(WRITE ${WORK}/missing.scn "<Node name=\"root\">\n <Node name=\"a\">\n  <EulerImplicitSolver/>\n  <CGLinearSolver/>\n  <MeshGmshLoader name=\"l\" filename=\"nowhere.msh\"/>\n  <MechanicalObject src=\"@l\"/>\n </Node>\n</Node>\n")
execute_process(COMMAND ${HOF} run ${WORK}/missing.scn --deterministic --seconds 0.1 --quiet RESULT_VARIABLE rc ERROR_VARIABLE err)
if(rc EQUAL 0 OR NOT err MATCHES "nowhere.msh")
  message(FATAL_ERROR "missing mesh not reported (rc=${rc}): ${err}")
endif()
file(WRITE ${WORK}/bad.hof "<hof>\n  <mechanics scene=\"x.scn\"/>\n  <haptics renderer=\"Magic\"/>\n</hof>\n")
execute_process(COMMAND ${HOF} run ${WORK}/bad.hof --deterministic --quiet RESULT_VARIABLE rc ERROR_VARIABLE err)
if(rc EQUAL 0 OR NOT err MATCHES "bad.hof:3")
  message(FATAL_ERROR "bad project not reported with its line (rc=${rc}): ${err}")
endif()

# An H3D X3D scene: its DeformableShape is driven by the mechanics (springs on its triangles).
execute_process(COMMAND ${HOF} run ${ANCHORS}/h3d/examples/All/DeformableShape.x3d --deterministic --seconds 3
                        --device "scripted:poke,start=0;0;0.1,direction=0;0;-1,approach=0.1,depth=0.01,speed=0.05,hold=0.2"
                        --quiet --out ${WORK}/x3d RESULT_VARIABLE rc ERROR_VARIABLE err)
if(NOT rc EQUAL 0)
  message(FATAL_ERROR "hof run DeformableShape.x3d failed (${rc}): ${err}")
endif()
file(READ ${WORK}/x3d/summary.json summary)
string(JSON contact GET "${summary}" contact_time_s)
string(JSON moved GET "${summary}" models 0 max_displacement_m)
if(contact LESS_EQUAL 0 OR moved LESS_EQUAL 0.001)
  message(FATAL_ERROR "the X3D deformable shape was not touched and deformed: contact ${contact} s, moved ${moved} m")
endif()

# The default probe: every bundled example and every anchor scene with a touchable body runs
# with `--device auto` and touches something: contact time > 0, the touched body moves (or is
# rigid), no fall-through, the force below the device's limit most of the time.
file(GLOB scenes ${SOURCE}/examples/*.hof ${SOURCE}/examples/*.scn ${ANCHORS}/sofa/*.scn ${ANCHORS}/sofa/history/2008-07-30*/liver.scn
     ${ANCHORS}/h3d/examples/All/DeformableShape.x3d ${ANCHORS}/h3d/examples/All/Surfaces.x3d
     ${ANCHORS}/h3d/examples/All/HapticsOptions.x3d ${ANCHORS}/h3d/examples/All/HapticLayeredGroup.x3d)
set(i 0)
foreach(scene ${scenes})
  math(EXPR i "${i} + 1")
  execute_process(COMMAND ${HOF} run ${scene} --device auto --deterministic --seconds 3 --quiet --out ${WORK}/probe${i}
                  RESULT_VARIABLE rc ERROR_VARIABLE err)
  if(NOT rc EQUAL 0)
    message(FATAL_ERROR "hof run ${scene} --device auto failed (${rc}): ${err}")
  endif()
  file(READ ${WORK}/probe${i}/summary.json summary)
  string(JSON contact GET "${summary}" contact_time_s)
  string(JSON fall GET "${summary}" fall_through_events)
  string(JSON clamped GET "${summary}" contact_time_at_force_limit_share)
  string(JSON kind GET "${summary}" bodies 0 kind)
  string(JSON moved GET "${summary}" bodies 0 max_displacement)
  string(JSON inside GET "${summary}" bodies 0 probe_started_inside)
  if(contact LESS_EQUAL 0.2 OR NOT fall EQUAL 0 OR clamped GREATER 0.01 OR inside)
    message(FATAL_ERROR "${scene} with the default probe: contact ${contact} s, fall-through ${fall}, "
                        "clamped share ${clamped}, started inside ${inside}")
  endif()
  if(kind STREQUAL "deformable" AND moved LESS_EQUAL 0)
    message(FATAL_ERROR "${scene} with the default probe: the touched body did not move")
  endif()
endforeach()

# Effect-only worlds run: H3D's SpringEffect example has no shape at all.
execute_process(COMMAND ${HOF} run ${ANCHORS}/h3d/examples/All/SpringEffect.x3d --deterministic --seconds 2 --quiet --out ${WORK}/spring
                RESULT_VARIABLE rc ERROR_VARIABLE err)
file(READ ${WORK}/spring/summary.json summary)
string(JSON force GET "${summary}" max_force_n)
if(NOT rc EQUAL 0 OR force LESS_EQUAL 0.1)
  message(FATAL_ERROR "SpringEffect.x3d did not run or felt nothing (rc ${rc}, max force ${force}): ${err}")
endif()

# A report is never lost: names that are not UTF-8 (a Latin-1 file) are escaped.
string(ASCII 223 sharp_s)
file(WRITE ${WORK}/latin1.x3d "<?xml version='1.0' encoding='ISO-8859-1'?>\n<X3D><Scene><Shape DEF='Gr")
file(APPEND ${WORK}/latin1.x3d "${sharp_s}e'><Appearance><SmoothSurface/></Appearance><Box size='0.1 0.1 0.1'/></Shape></Scene></X3D>\n")
execute_process(COMMAND ${HOF} run ${WORK}/latin1.x3d --deterministic --seconds 2 --quiet --out ${WORK}/latin1
                RESULT_VARIABLE rc ERROR_VARIABLE err)
if(NOT rc EQUAL 0 OR NOT EXISTS ${WORK}/latin1/summary.json)
  message(FATAL_ERROR "a Latin-1 scene lost its report (rc ${rc}): ${err}")
endif()
file(READ ${WORK}/latin1/summary.json summary)
string(JSON name GET "${summary}" bodies 0 name)
if(NOT name MATCHES "^Gr.*e$")
  message(FATAL_ERROR "the Latin-1 body name was not kept (escaped): ${name}")
endif()

# A newline in a body name (&#10;) once ended the gnuplot title mid-string and lost every
# plot of a run that touched the body: control characters are written as spaces.
file(WRITE ${WORK}/newline.x3d "<?xml version='1.0'?>\n<X3D><Scene><Shape DEF='Two&#10;lines'><Appearance>"
     "<SmoothSurface/></Appearance><Box size='0.1 0.1 0.1'/></Shape></Scene></X3D>\n")
execute_process(COMMAND ${HOF} run ${WORK}/newline.x3d --deterministic --seconds 2 --quiet --out ${WORK}/newline
                RESULT_VARIABLE rc ERROR_VARIABLE err)
file(READ ${WORK}/newline/plots.gp plots)
if(NOT rc EQUAL 0 OR NOT plots MATCHES "set title 'newline.x3d - Two lines'\n")
  message(FATAL_ERROR "a body name with a newline broke the plot scripts (rc ${rc}): ${err}")
endif()
find_program(GNUPLOT gnuplot)
if(GNUPLOT AND NOT EXISTS ${WORK}/newline/force_over_time.png)
  message(FATAL_ERROR "a body name with a newline lost the plots: ${err}")
endif()

# Numeric options are range-checked with a clear message starting with `hof:`.
foreach(bad "--telemetry-rate;-5" "--seconds;1e9" "--seconds;0" "--steps;-3")
  execute_process(COMMAND ${HOF} run ${SOURCE}/examples/liver-palpation-simple.hof --deterministic ${bad} --quiet
                  RESULT_VARIABLE rc ERROR_VARIABLE err)
  if(rc EQUAL 0 OR NOT err MATCHES "^hof: ")
    message(FATAL_ERROR "hof run ${bad} was not refused clearly (rc ${rc}): ${err}")
  endif()
endforeach()

# check and run agree on a scene with nothing to touch: H3DViewer opens it, so check reports it
# (naming what is not modelled) without failing, and run exits with its own code (5).
file(WRITE ${WORK}/nothing.x3d "<X3D><Scene><PythonScript url='x.py'/><Shape><Box/></Shape></Scene></X3D>\n")
execute_process(COMMAND ${HOF} check ${WORK}/nothing.x3d RESULT_VARIABLE rc ERROR_VARIABLE err OUTPUT_VARIABLE out)
if(NOT rc EQUAL 0 OR NOT out MATCHES "PythonScript" OR NOT out MATCHES "nothing to touch")
  message(FATAL_ERROR "hof check did not report a scene with nothing to touch (rc ${rc}): ${out}${err}")
endif()
execute_process(COMMAND ${HOF} run ${WORK}/nothing.x3d --deterministic --quiet RESULT_VARIABLE rc ERROR_VARIABLE err)
if(NOT rc EQUAL 5 OR NOT err MATCHES "nothing to touch")
  message(FATAL_ERROR "hof run on a scene with nothing to touch did not exit 5 (rc ${rc}): ${err}")
endif()

# A project whose scene is broken: the error names the project, then the scene (resolved).
file(WRITE ${WORK}/points-to-missing.hof "<hof>\n  <mechanics scene=\"missing.scn\"/>\n</hof>\n")
execute_process(COMMAND ${HOF} run ${WORK}/points-to-missing.hof --deterministic --quiet RESULT_VARIABLE rc ERROR_VARIABLE err)
if(rc EQUAL 0 OR NOT err MATCHES "^hof: [^\n]*points-to-missing.hof: its scene [^\n]*/missing.scn:[0-9]+: [^\n]*nowhere.msh")
  message(FATAL_ERROR "a project's broken scene was not reported project first (rc=${rc}): ${err}")
endif()

# The needle example, as the issue runs it (no --seconds: the scripted insert–hold–extract is
# played whole): every phase is visited, the capsule breaks, and the force-against-depth plot
# (with the model's curve) is written.
execute_process(COMMAND ${HOF} run ${SOURCE}/examples/needle-liver.hof --headless --deterministic --quiet --out ${WORK}/needle
                RESULT_VARIABLE rc ERROR_VARIABLE err)
if(NOT rc EQUAL 0)
  message(FATAL_ERROR "hof run needle-liver.hof failed (${rc}): ${err}")
endif()
file(READ ${WORK}/needle/summary.json summary)
foreach(phase free touching pre-puncture punctured relaxation extraction out)
  string(JSON t GET "${summary}" needle phase_time_s ${phase})
  if(t LESS_EQUAL 0)
    message(FATAL_ERROR "needle-liver.hof: the needle never was in phase ${phase}")
  endif()
endforeach()
string(JSON puncture GET "${summary}" needle puncture_depth_m)
string(JSON moved GET "${summary}" bodies 0 max_displacement)
if(puncture LESS 0.019 OR puncture GREATER 0.021 OR moved LESS_EQUAL 0.001)
  message(FATAL_ERROR "needle-liver.hof: puncture at ${puncture} m (capsule 0.02 m), liver moved ${moved} m")
endif()
foreach(f force_vs_depth.png force_vs_depth.svg needle_force_over_time.png needle_model.dat)
  if(NOT EXISTS ${WORK}/needle/${f})
    message(FATAL_ERROR "needle-liver.hof: no ${f} in the report")
  endif()
endforeach()
file(STRINGS ${WORK}/needle/telemetry.csv header LIMIT_COUNT 1)
if(NOT header MATCHES ",depth,phase,needle_force,sent_axial_force,press$")
  message(FATAL_ERROR "needle-liver.hof: telemetry without the needle's columns: ${header}")
endif()
