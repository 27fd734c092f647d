# SPDX-License-Identifier: Apache-2.0
# `cmake --install`: the rigcal command, the libraries with their public headers and a CMake
# package, so that another project writes
#   find_package(rigcal REQUIRED)
#   target_link_libraries(app PRIVATE rigcal::calib rigcal::vo)
# Components: `runtime` (bin/rigcal, example configs, systemd units) and `dev` (headers, static
# libraries, CMake package, LCM types: lcmtypes/CMakeLists.txt). CPack makes one Debian
# package of each (cmake/RigcalPackaging.cmake).
include(CMakePackageConfigHelpers)

# rigcal_<name> is exported as rigcal::<name>; the same names exist in this tree as aliases.
set(RIGCAL_EXPORTED_LIBRARIES rigcal_trigger_protocol rigcal_trigger_core rigcal_base rigcal_calib
    rigcal_camera rigcal_capture rigcal_trigger rigcal_sim rigcal_vo rigcal_io rigcal_plot
    rigcal_pattern rigcal_lcmtypes rigcal_lcm rigcal_pipeline rigcal_monitor rigcal_report)
if(TARGET rigcal_research)
  list(APPEND RIGCAL_EXPORTED_LIBRARIES rigcal_research)
endif()

set(RIGCAL_CMAKE_INSTALL_DIR ${CMAKE_INSTALL_LIBDIR}/cmake/rigcal)
foreach(target ${RIGCAL_EXPORTED_LIBRARIES})
  string(REGEX REPLACE "^rigcal_" "" name ${target})
  set_target_properties(${target} PROPERTIES EXPORT_NAME ${name})
  add_library(rigcal::${name} ALIAS ${target})
  get_target_property(header_dir ${target} RIGCAL_PUBLIC_HEADER_DIR)
  if(header_dir)
    install(DIRECTORY ${header_dir}/ DESTINATION ${CMAKE_INSTALL_INCLUDEDIR} COMPONENT dev
            FILES_MATCHING PATTERN "*.h")
  endif()
endforeach()

install(TARGETS ${RIGCAL_EXPORTED_LIBRARIES} EXPORT rigcalTargets
        ARCHIVE DESTINATION ${CMAKE_INSTALL_LIBDIR} COMPONENT dev
        LIBRARY DESTINATION ${CMAKE_INSTALL_LIBDIR} COMPONENT dev
        INCLUDES DESTINATION ${CMAKE_INSTALL_INCLUDEDIR})
install(TARGETS rigcal RUNTIME DESTINATION ${CMAKE_INSTALL_BINDIR} COMPONENT runtime)
install(EXPORT rigcalTargets NAMESPACE rigcal:: DESTINATION ${RIGCAL_CMAKE_INSTALL_DIR}
        COMPONENT dev)

configure_package_config_file(${PROJECT_SOURCE_DIR}/cmake/rigcalConfig.cmake.in
                              ${PROJECT_BINARY_DIR}/rigcalConfig.cmake
                              INSTALL_DESTINATION ${RIGCAL_CMAKE_INSTALL_DIR})
write_basic_package_version_file(${PROJECT_BINARY_DIR}/rigcalConfigVersion.cmake
                                 COMPATIBILITY SameMinorVersion)
install(FILES ${PROJECT_BINARY_DIR}/rigcalConfig.cmake ${PROJECT_BINARY_DIR}/rigcalConfigVersion.cmake
        DESTINATION ${RIGCAL_CMAKE_INSTALL_DIR} COMPONENT dev)

# Example rig configurations (share/rigcal/config) and the service units (config/systemd).
install(DIRECTORY ${PROJECT_SOURCE_DIR}/config/ DESTINATION ${CMAKE_INSTALL_DATADIR}/rigcal/config
        COMPONENT runtime FILES_MATCHING PATTERN "*.yaml" PATTERN "systemd" EXCLUDE
        PATTERN "examples" EXCLUDE)
# The documentation (docs/*.md: config reference, usage, deployment, ...) beside the licence.
install(DIRECTORY ${PROJECT_SOURCE_DIR}/docs/ DESTINATION ${CMAKE_INSTALL_DATADIR}/doc/rigcal
        COMPONENT runtime FILES_MATCHING PATTERN "*.md")
# Rigs of real cameras to start from (share/rigcal/examples): the triggered stereo pair, a
# 4-camera surround rig on v4l2, a libcamera pair. The stereo pair is also /etc/rigcal/rig.yaml,
# the config both units read (a conffile of the .deb: an edited one survives upgrades).
set(rigcal_examples ${PROJECT_SOURCE_DIR}/config/stereo_v4l2_trigger.yaml
    ${PROJECT_SOURCE_DIR}/config/examples/surround4_v4l2.yaml
    ${PROJECT_SOURCE_DIR}/config/examples/libcamera_stereo.yaml)
install(FILES ${rigcal_examples} DESTINATION ${CMAKE_INSTALL_DATADIR}/rigcal/examples
        COMPONENT runtime)
# /etc for the /usr prefix (the .deb), <prefix>/etc otherwise; decided at install time, when the
# prefix is known (as GNUInstallDirs does for SYSCONFDIR).
install(CODE "
  if(CMAKE_INSTALL_PREFIX STREQUAL \"/usr\")
    set(etc \"/etc\")
  else()
    set(etc \"\${CMAKE_INSTALL_PREFIX}/etc\")
  endif()
  file(INSTALL \"${PROJECT_SOURCE_DIR}/config/stereo_v4l2_trigger.yaml\"
       DESTINATION \"\${etc}/rigcal\" RENAME rig.yaml)"
  COMPONENT runtime)

# systemd units (config/systemd, docs/deployment.md): rigcal.service runs `rigcal calib` with
# the watchdog, rigcal-run.service `rigcal run` on this computer's cameras, rigcal-health.timer
# runs `rigcal status --once` every minute. The units name
# the installed rigcal, whose path is known only at install time (cmake --install --prefix,
# CPack's /usr): @bindir@ and @datadir@ are filled in then, straight into the destination.
set(RIGCAL_SYSTEMD_UNIT_DIR "lib/systemd/system" CACHE STRING
    "Where `cmake --install` puts the systemd units (relative to the prefix)")
foreach(unit rigcal.service rigcal-run.service rigcal-health.service)
  install(CODE "
    set(bindir \"\${CMAKE_INSTALL_PREFIX}/${CMAKE_INSTALL_BINDIR}\")
    set(datadir \"\${CMAKE_INSTALL_PREFIX}/${CMAKE_INSTALL_DATADIR}\")
    set(unit \"\$ENV{DESTDIR}\${CMAKE_INSTALL_PREFIX}/${RIGCAL_SYSTEMD_UNIT_DIR}/${unit}\")
    message(STATUS \"Installing: \${unit}\")
    configure_file(\"${PROJECT_SOURCE_DIR}/config/systemd/${unit}.in\" \"\${unit}\" @ONLY)"
    COMPONENT runtime)
endforeach()
install(FILES ${PROJECT_SOURCE_DIR}/config/systemd/rigcal-health.timer
        DESTINATION ${RIGCAL_SYSTEMD_UNIT_DIR} COMPONENT runtime)
install(FILES ${PROJECT_SOURCE_DIR}/config/systemd/rigcal.default
        DESTINATION ${CMAKE_INSTALL_DATADIR}/rigcal/config/systemd COMPONENT runtime)

include(RigcalPackaging)  # cpack -G DEB: the rigcal and rigcal-dev packages
