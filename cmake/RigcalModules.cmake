# SPDX-License-Identifier: Apache-2.0
# The modules of rigcal and what each may use (docs/architecture.md "Layers"). One table for
# the build (the link graph written for the check), the layer check
# (tests/architecture/check_layers.cmake) and the docs (the check compares their layer table
# with this one).
#   rigcal_module(<name> TARGET <target> DIRS <folders...> USES <modules...>)
# A module may include the public headers (rigcal/<module>/...) of, and link, only itself and
# the modules it USES, directly or through them. NO_OPENCV: neither includes nor links OpenCV.
set(RIGCAL_MODULES "")
macro(rigcal_module name)
  cmake_parse_arguments(RIGCAL_MODULE_ARG "NO_OPENCV" "TARGET" "DIRS;USES" ${ARGN})
  list(APPEND RIGCAL_MODULES ${name})
  set(RIGCAL_MODULE_TARGET_${name} ${RIGCAL_MODULE_ARG_TARGET})
  set(RIGCAL_MODULE_DIRS_${name} ${RIGCAL_MODULE_ARG_DIRS})
  set(RIGCAL_MODULE_USES_${name} ${RIGCAL_MODULE_ARG_USES})
  set(RIGCAL_MODULE_NO_OPENCV_${name} ${RIGCAL_MODULE_ARG_NO_OPENCV})
endmacro()

# Firmware: nothing of the host code.
rigcal_module(trigger_protocol TARGET rigcal_trigger_protocol DIRS firmware/protocol NO_OPENCV)
rigcal_module(trigger_core TARGET rigcal_trigger_core DIRS firmware/core firmware/board
              USES trigger_protocol NO_OPENCV)
# calib: the vocabulary, the camera models, the estimators.
rigcal_module(base TARGET rigcal_base DIRS calib/base NO_OPENCV)
rigcal_module(camera TARGET rigcal_camera DIRS calib/camera USES base NO_OPENCV)
rigcal_module(calib TARGET rigcal_calib DIRS calib/src calib/include USES base NO_OPENCV)
# drivers (capture, trigger, sim) and vo: frames and poses; never the estimators. The hardware
# side (capture, trigger) never uses the simulator.
rigcal_module(capture TARGET rigcal_capture DIRS drivers/capture USES base)
rigcal_module(trigger TARGET rigcal_trigger DIRS drivers/trigger
              USES base capture trigger_protocol)
rigcal_module(sim TARGET rigcal_sim DIRS drivers/sim
              USES base camera capture trigger trigger_core)
rigcal_module(vo TARGET rigcal_vo DIRS vo USES base camera)
# tools: at most five floors (io < lcm < pipeline < research < cli).
rigcal_module(io TARGET rigcal_io DIRS tools/io USES calib camera capture trigger sim)
rigcal_module(plot TARGET rigcal_plot DIRS tools/plot USES io)
rigcal_module(pattern TARGET rigcal_pattern DIRS tools/pattern USES io)
rigcal_module(lcm TARGET rigcal_lcm DIRS tools/lcm USES io)
rigcal_module(pipeline TARGET rigcal_pipeline DIRS tools/pipeline USES lcm vo)
rigcal_module(monitor TARGET rigcal_monitor DIRS tools/monitor USES lcm)
rigcal_module(report TARGET rigcal_report DIRS tools/report USES lcm plot)
rigcal_module(research TARGET rigcal_research DIRS tools/research USES pipeline plot)
rigcal_module(cli TARGET rigcal DIRS tools/cli USES research report monitor pattern)

# rigcal_module_closure(<module> <out-var>): the module and every module it uses, transitively.
function(rigcal_module_closure module out)
  set(closure ${module})
  set(todo ${module})
  while(todo)
    list(POP_FRONT todo m)
    foreach(u ${RIGCAL_MODULE_USES_${m}})
      if(NOT u IN_LIST closure)
        list(APPEND closure ${u})
        list(APPEND todo ${u})
      endif()
    endforeach()
  endwhile()
  set(${out} ${closure} PARENT_SCOPE)
endfunction()
