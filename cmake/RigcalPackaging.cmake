# SPDX-License-Identifier: Apache-2.0
# Debian packages through CPack (`cpack -G DEB` in a build tree, docs/deployment.md):
#   rigcal      bin/rigcal, example configs, systemd units      (component runtime)
#   rigcal-dev  headers, static libraries, CMake package, LCM    (component dev)
#               definitions, generated C++/Python/Java types
# Dependencies: dpkg-shlibdeps on the binary (SHLIBDEPS) for a native build. A cross build
# (scripts/cross-arm64.sh) has no arm64 dpkg database to ask, so it passes the list the amd64
# package got as RIGCAL_DEB_DEPENDS: the same sources against the same Debian release need the
# same sonames, hence the same packages (tests/install/arm64_qemu_test.sh compares the NEEDED
# entries of both binaries).
set(CPACK_PACKAGE_NAME rigcal)
set(CPACK_PACKAGE_VENDOR "rigcal")
# No project address exists yet: -DCPACK_PACKAGE_CONTACT="Name <address>" when packaging.
set(CPACK_PACKAGE_CONTACT "rigcal maintainers <rigcal@example.org>" CACHE STRING
    "Maintainer of the Debian packages")
set(CPACK_PACKAGE_DESCRIPTION_SUMMARY "online extrinsic calibration of multi-camera rigs")
set(CPACK_PACKAGE_VERSION ${PROJECT_VERSION})
set(CPACK_GENERATOR DEB)
set(CPACK_DEB_COMPONENT_INSTALL ON)
set(CPACK_COMPONENTS_ALL runtime dev)
set(CPACK_PACKAGING_INSTALL_PREFIX /usr)
set(CPACK_STRIP_FILES ON)
set(CPACK_DEBIAN_FILE_NAME DEB-DEFAULT)
set(CPACK_DEBIAN_PACKAGE_SECTION science)
set(CPACK_DEBIAN_PACKAGE_PRIORITY optional)
set(CPACK_DEBIAN_PACKAGE_RELEASE 1)
set(CPACK_DEBIAN_PACKAGE_HOMEPAGE "https://example.invalid/rigcal")
# Architecture: dpkg --print-architecture, or CPACK_DEBIAN_PACKAGE_ARCHITECTURE from the
# command line (the cross build passes arm64).

set(CPACK_DEBIAN_RUNTIME_PACKAGE_NAME rigcal)
set(CPACK_DEBIAN_RUNTIME_PACKAGE_SECTION science)
# Synopsis: CPACK_PACKAGE_DESCRIPTION_SUMMARY; these are the extended descriptions (lines of at
# most 80 characters, lintian).
set(CPACK_COMPONENT_RUNTIME_DESCRIPTION "rigcal estimates, while a vehicle drives, where every camera of a rig sits
relative to a master camera (rotation, position and odometry scale) from the
cameras' monocular visual odometry, and publishes the estimate over LCM. This
package holds the rigcal command, example rig configurations,
/etc/rigcal/rig.yaml and systemd units for the calibrator (on the bus, or on
this computer's cameras) and its health check.")
# /etc/rigcal/rig.yaml is a conffile: dpkg keeps the edited one across upgrades and removals.
file(WRITE ${PROJECT_BINARY_DIR}/deb/conffiles "/etc/rigcal/rig.yaml\n")
set(CPACK_DEBIAN_RUNTIME_PACKAGE_CONTROL_EXTRA ${PROJECT_BINARY_DIR}/deb/conffiles)
set(RIGCAL_DEB_DEPENDS "" CACHE STRING
    "Debian Depends of the rigcal package; empty = dpkg-shlibdeps (native builds)")
if(RIGCAL_DEB_DEPENDS)
  set(CPACK_DEBIAN_RUNTIME_PACKAGE_DEPENDS "${RIGCAL_DEB_DEPENDS}")
else()
  set(CPACK_DEBIAN_RUNTIME_PACKAGE_SHLIBDEPS ON)
endif()

set(CPACK_DEBIAN_DEV_PACKAGE_NAME rigcal-dev)
set(CPACK_DEBIAN_DEV_PACKAGE_SECTION libdevel)
set(CPACK_COMPONENT_DEV_DESCRIPTION "Headers, static libraries and the CMake package of rigcal: find_package(rigcal)
gives rigcal::calib, rigcal::capture, rigcal::vo and the others. Also the LCM
message definitions and their generated C++, Python and Java (lcm-spy) types.")
# The static libraries' own dependencies, as rigcalConfig.cmake finds them.
set(CPACK_DEBIAN_DEV_PACKAGE_DEPENDS
    "libeigen3-dev, libceres-dev, libspdlog-dev, libyaml-cpp-dev, nlohmann-json3-dev, \
libopencv-dev, liblcm-dev, libglib2.0-dev, pkg-config, python3")
set(CPACK_DEBIAN_DEV_PACKAGE_RECOMMENDS "rigcal (= ${PROJECT_VERSION}-1)")

# The licence (Apache-2.0, LICENSE) in Debian's machine-readable copyright format, in each
# package's doc directory (Debian policy 12.5).
install(FILES ${PROJECT_SOURCE_DIR}/cmake/debian/copyright
        DESTINATION ${CMAKE_INSTALL_DATADIR}/doc/rigcal COMPONENT runtime)
install(FILES ${PROJECT_SOURCE_DIR}/cmake/debian/copyright
        DESTINATION ${CMAKE_INSTALL_DATADIR}/doc/rigcal-dev COMPONENT dev)
set(CPACK_RESOURCE_FILE_LICENSE ${PROJECT_SOURCE_DIR}/LICENSE)

# The Debian changelog every binary package carries (policy 12.7; lintian's no-changelog): one
# entry for this version pointing to the project's history, dated at configure time (or
# SOURCE_DATE_EPOCH, which string(TIMESTAMP) honours, for a reproducible package), compressed
# with gzip -9n as lintian expects.
find_program(RIGCAL_GZIP gzip)
if(RIGCAL_GZIP)
  string(TIMESTAMP rigcal_changelog_date "%a, %d %b %Y %H:%M:%S +0000" UTC)
  file(WRITE ${PROJECT_BINARY_DIR}/deb/changelog.Debian
       "rigcal (${PROJECT_VERSION}-1) unstable; urgency=medium\n\n"
       "  * rigcal ${PROJECT_VERSION} packaged with CPack; the changes are the project's git\n"
       "    history.\n\n"
       " -- ${CPACK_PACKAGE_CONTACT}  ${rigcal_changelog_date}\n")
  execute_process(COMMAND ${RIGCAL_GZIP} -9nf ${PROJECT_BINARY_DIR}/deb/changelog.Debian
                  RESULT_VARIABLE rigcal_gzip_result)
  if(rigcal_gzip_result EQUAL 0)
    install(FILES ${PROJECT_BINARY_DIR}/deb/changelog.Debian.gz
            DESTINATION ${CMAKE_INSTALL_DATADIR}/doc/rigcal COMPONENT runtime)
    install(FILES ${PROJECT_BINARY_DIR}/deb/changelog.Debian.gz
            DESTINATION ${CMAKE_INSTALL_DATADIR}/doc/rigcal-dev COMPONENT dev)
  endif()
endif()

include(CPack)
