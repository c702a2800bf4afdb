# Runs at install time (install(SCRIPT) in the top-level CMakeLists.txt), when
# CMAKE_INSTALL_PREFIX is the prefix `cmake --install --prefix` names, not the configured one.
# The units in systemd/ name /usr/bin and /usr/share/doc/omega, which fits the packaged prefix
# /usr; under any other prefix a unit copied as it is would start a program that is not there.
# OMEGA_UNIT_SOURCE and OMEGA_UNIT_STAGING are set by an install(CODE) just before.
if(CMAKE_INSTALL_PREFIX MATCHES "[ \t\n]")
  # ExecStart= would split the path at the blank and start something else.
  message(WARNING "systemd units not installed: the prefix '${CMAKE_INSTALL_PREFIX}' contains a blank")
  return()
endif()
foreach(unit omegad.service omegad.socket omega-worker.service)
  file(READ "${OMEGA_UNIT_SOURCE}/${unit}" text)
  string(REPLACE "=/usr/bin/" "=${CMAKE_INSTALL_PREFIX}/bin/" text "${text}")
  string(REPLACE "file:/usr/share/doc/omega/" "file:${CMAKE_INSTALL_PREFIX}/share/doc/omega/" text "${text}")
  file(WRITE "${OMEGA_UNIT_STAGING}/${unit}" "${text}")
endforeach()
# file(INSTALL) applies DESTDIR and records the files in install_manifest.txt, as install(FILES)
# would have.
file(INSTALL DESTINATION "${CMAKE_INSTALL_PREFIX}/lib/systemd/system" TYPE FILE
     FILES "${OMEGA_UNIT_STAGING}/omegad.service" "${OMEGA_UNIT_STAGING}/omegad.socket"
           "${OMEGA_UNIT_STAGING}/omega-worker.service")
