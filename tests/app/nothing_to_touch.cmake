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
# A file that is not an X3D scene stays an error (status 1).
set(fragment ${WORK}/device.x3d)
file(WRITE ${fragment} "<DeviceInfo><AnyDevice/></DeviceInfo>\n")
execute_process(COMMAND ${HOF} run ${fragment} --quiet RESULT_VARIABLE rc ERROR_VARIABLE err)
if(NOT rc EQUAL 1 OR NOT err MATCHES "not an X3D scene: its root element is <DeviceInfo>")
  message(FATAL_ERROR "hof run on a settings fragment: status ${rc}, stderr:\n${err}")
endif()
