# Issue 35: an X3D scene with nothing to touch opens as H3DViewer opens it. `hof check`
# reports it and succeeds; `hof run` exits with its own status (5) and one line naming why.
file(MAKE_DIRECTORY ${WORK})
set(scene ${WORK}/seen-only.x3d)
file(WRITE ${scene} "<X3D><Scene><Shape><Appearance><Material/></Appearance><Box size='0.1 0.1 0.1'/></Shape></Scene></X3D>\n")
execute_process(COMMAND ${HOF} check ${scene} RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
if(NOT rc EQUAL 0 OR NOT out MATCHES "warning: .*nothing to touch: 1 shape is only seen")
  message(FATAL_ERROR "hof check: status ${rc}, output:\n${out}${err}")
endif()
execute_process(COMMAND ${HOF} run ${scene} --deterministic --seconds 0.1 --quiet RESULT_VARIABLE rc OUTPUT_VARIABLE out
                ERROR_VARIABLE err)
if(NOT rc EQUAL 5 OR NOT err STREQUAL "hof: ${scene}: nothing to touch: 1 shape is only seen (no haptic surface in its Appearance), and no force effect; `hof gui` shows it\n")
  message(FATAL_ERROR "hof run: status ${rc} (5 expected), stderr:\n${err}")
endif()
# A settings file (H3DViewer opens it) opens with nothing to touch (status 5); a file whose
# root is no X3D node is not an X3D file: an error (status 1).
set(fragment ${WORK}/device.x3d)
file(WRITE ${fragment} "<DeviceInfo><AnyDevice/></DeviceInfo>\n")
execute_process(COMMAND ${HOF} run ${fragment} --deterministic --seconds 0.1 --quiet RESULT_VARIABLE rc ERROR_VARIABLE err)
if(NOT rc EQUAL 5 OR NOT err MATCHES "nothing to touch: no Shape")
  message(FATAL_ERROR "hof run on a settings file: status ${rc} (5 expected), stderr:\n${err}")
endif()
set(not_x3d ${WORK}/picture.x3d)
file(WRITE ${not_x3d} "<svg><rect/></svg>\n")
execute_process(COMMAND ${HOF} run ${not_x3d} --quiet RESULT_VARIABLE rc ERROR_VARIABLE err)
if(NOT rc EQUAL 1 OR NOT err MATCHES "not an X3D scene: its root element <svg> is not an X3D node")
  message(FATAL_ERROR "hof run on a file that is not X3D: status ${rc}, stderr:\n${err}")
endif()
