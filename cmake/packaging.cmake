# Installing and packaging (docs/install.md). `cmake --install build --prefix P`
# lays the programs out as a desktop expects: P/bin, the data folder
# P/share/simpartner (app/data/data_files.h finds it beside P/bin, so the
# literal "bin" and "share" here, not GNUInstallDirs' settable ones), the
# desktop entry, the icon in the hicolor theme, man pages and the docs.
# `cpack` in the build folder makes a .deb of the same tree.

# Installing (and cpack's "preinstall") takes the build as it is, never
# builds: cpack runs from a test while other tests use the build tree.
set(CMAKE_SKIP_INSTALL_ALL_DEPENDENCY ON)
install(TARGETS simpartner simpartner-sim simpartner-robot RUNTIME DESTINATION bin)
install(DIRECTORY robots terrains config DESTINATION share/simpartner)
install(DIRECTORY docs/ DESTINATION share/doc/simpartner)
install(FILES README.md packaging/copyright DESTINATION share/doc/simpartner)
install(FILES assets/simpartner.desktop DESTINATION share/applications)
install(FILES assets/icons/simpartner.svg DESTINATION share/icons/hicolor/scalable/apps)
foreach(size 16 24 32 48 64 128 256)
  install(FILES assets/icons/hicolor/${size}x${size}/simpartner.png DESTINATION share/icons/hicolor/${size}x${size}/apps)
endforeach()

# Debian wants the changelog and man pages compressed, without timestamps (-n).
configure_file(packaging/changelog ${PROJECT_BINARY_DIR}/packaging/changelog @ONLY)
add_custom_command(OUTPUT packaging/changelog.gz
  COMMAND gzip -9nkf packaging/changelog
  DEPENDS ${PROJECT_BINARY_DIR}/packaging/changelog)
set(sp_packaged ${PROJECT_BINARY_DIR}/packaging/changelog.gz)
install(FILES ${PROJECT_BINARY_DIR}/packaging/changelog.gz DESTINATION share/doc/simpartner)

# Man pages from each program's --help (help2man; scripts/install-deps.sh installs it).
find_program(HELP2MAN help2man)
if(HELP2MAN)
  set(sp_man_simpartner "the WorkPartner operator console with its physics twin")
  set(sp_man_simpartner-sim "the headless WorkPartner twin: check, run, validate, rehearse, sweep")
  set(sp_man_simpartner-robot "the WorkPartner twin as a robot on the SimPartner link protocol")
  foreach(tool simpartner simpartner-sim simpartner-robot)
    add_custom_command(OUTPUT man/${tool}.1.gz
      COMMAND ${CMAKE_COMMAND} -E make_directory man
      COMMAND ${CMAKE_COMMAND} -E env QT_QPA_PLATFORM=offscreen
              ${HELP2MAN} --no-info --no-discard-stderr "--name=${sp_man_${tool}}" --output=man/${tool}.1 $<TARGET_FILE:${tool}>
      COMMAND gzip -9nf man/${tool}.1
      DEPENDS ${tool}
      COMMENT "Man page of ${tool}")
    list(APPEND sp_packaged ${PROJECT_BINARY_DIR}/man/${tool}.1.gz)
    install(FILES ${PROJECT_BINARY_DIR}/man/${tool}.1.gz DESTINATION share/man/man1)
  endforeach()
else()
  message(STATUS "help2man not found: no man pages (scripts/install-deps.sh installs it)")
endif()
add_custom_target(packaging_files ALL DEPENDS ${sp_packaged})

# The .deb: its dependencies are the Debian 12 packages the programs link
# (dpkg-shlibdeps), plus Qt's platform plugins, which nothing links but the
# console needs to open a window.
set(CPACK_GENERATOR DEB)
# Everything but the ROS component (ros/CMakeLists.txt): the package depends on no ROS library.
set(CPACK_INSTALL_CMAKE_PROJECTS "${PROJECT_BINARY_DIR};${PROJECT_NAME};Unspecified;/")
set(CPACK_PACKAGE_NAME simpartner)
set(CPACK_PACKAGE_VENDOR "SimPartner")
set(CPACK_PACKAGE_CONTACT "SimPartner team <simpartner@example.org>")
set(CPACK_PACKAGE_DESCRIPTION_SUMMARY "operator console with a physics twin for the WorkPartner robot")
# The synopsis is the summary above; CPack indents this body itself.
set(CPACK_DEBIAN_PACKAGE_DESCRIPTION "SimPartner previews an operator's commands on a real-time ODE twin of the
WorkPartner service robot before relaying them over TCP, with a predictive
ghost for delayed links, rehearsal of command sequences, replay of logged
sessions and terrain editing. Includes the headless twin (simpartner-sim)
and a stand-in robot that speaks the link protocol (simpartner-robot).")
set(CPACK_DEBIAN_PACKAGE_SECTION science)
set(CPACK_DEBIAN_PACKAGE_SHLIBDEPS ON)
set(CPACK_DEBIAN_PACKAGE_DEPENDS "qt6-qpa-plugins")
set(CPACK_DEBIAN_FILE_NAME DEB-DEFAULT)
set(CPACK_PACKAGING_INSTALL_PREFIX /usr)
set(CPACK_STRIP_FILES ON)
set(CPACK_DEBIAN_PACKAGE_CONTROL_STRICT_PERMISSION TRUE)
include(CPack)
