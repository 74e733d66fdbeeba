# install.cmake: the install steps whose paths depend on the prefix given
# at install time (`cmake --install BUILD --prefix P`, or CPack's /usr),
# which install() rules with fixed destinations cannot know at configure
# time. Included by install(CODE) in the top-level CMakeLists.txt, which
# sets:
#   WSG_PKG_SRC     the source's packaging/ directory
#   WSG_PKG_BIN     a scratch directory in the build tree
#   WSG_BINDIR      CMAKE_INSTALL_BINDIR (relative to the prefix, or absolute)
#   WSG_SYSCONFDIR  CMAKE_INSTALL_SYSCONFDIR (likewise)
#   WSG_UNITDIR     the systemd unit directory (likewise)
# It installs
#   SYSCONFDIR/wsgemu/wsgemu.conf   the service's settings, from
#                                   packaging/wsgemu.conf; an existing file
#                                   is kept, as it holds the admin's edits
#   UNITDIR/wsgemu.service          with ExecStart naming this prefix's
#                                   program and config file
#   UNITDIR/wsgemu@.service         the template (an emulator per config
#                                   file, SYSCONFDIR/wsgemu/NAME.conf),
#                                   its ExecStart written likewise
#   SYSCONFDIR/logrotate.d/wsgemu   packaging/wsgemu.logrotate; an existing
#                                   file is kept, like the config file
# Absolute paths come from GNUInstallDirs' own rule, applied to the prefix
# of this install: /etc for the prefixes / and /usr, /etc/opt/X for /opt/X,
# else PREFIX/etc; other directories below the prefix unless absolute.
# DESTDIR (CPack's staging directory) is applied by file(INSTALL) as usual,
# and is not part of any path written into the units.

# Set only so that GNUInstallDirs, outside a project, need not guess it.
set(CMAKE_INSTALL_LIBDIR lib)
include(GNUInstallDirs)
GNUInstallDirs_get_absolute_install_dir(wsg_etc WSG_SYSCONFDIR SYSCONFDIR)
GNUInstallDirs_get_absolute_install_dir(wsg_bindir WSG_BINDIR BINDIR)
GNUInstallDirs_get_absolute_install_dir(wsg_unitdir WSG_UNITDIR UNITDIR)
set(wsg_confdir "${wsg_etc}/wsgemu")

# The config file: never overwrite one that is there (the Debian package
# marks it a conffile, so dpkg asks instead).
if(EXISTS "$ENV{DESTDIR}${wsg_confdir}/wsgemu.conf")
  message(STATUS
    "Keeping: $ENV{DESTDIR}${wsg_confdir}/wsgemu.conf (the example is in the doc directory)")
else()
  file(INSTALL DESTINATION "${wsg_confdir}" TYPE FILE
       FILES "${WSG_PKG_SRC}/wsgemu.conf")
endif()

# The logrotate snippet, kept like the config file.
if(EXISTS "$ENV{DESTDIR}${wsg_etc}/logrotate.d/wsgemu")
  message(STATUS "Keeping: $ENV{DESTDIR}${wsg_etc}/logrotate.d/wsgemu")
else()
  file(INSTALL DESTINATION "${wsg_etc}/logrotate.d" TYPE FILE
       FILES "${WSG_PKG_SRC}/wsgemu.logrotate" RENAME wsgemu)
endif()

# The units: the sources name the Debian paths; write this install's.
# wsgemu.service reads wsgemu.conf, the template wsgemu@.service NAME.conf
# (%i, its instance).
file(MAKE_DIRECTORY "${WSG_PKG_BIN}")
foreach(wsg_pair "wsgemu.service:wsgemu.conf" "wsgemu@.service:%i.conf")
  string(REPLACE ":" ";" wsg_pair "${wsg_pair}")
  list(GET wsg_pair 0 wsg_name)
  list(GET wsg_pair 1 wsg_conf)
  set(wsg_exec "ExecStart=/usr/bin/wsgemu --config /etc/wsgemu/${wsg_conf}")
  file(READ "${WSG_PKG_SRC}/${wsg_name}" wsg_unit)
  string(FIND "${wsg_unit}" "${wsg_exec}" wsg_at)
  if(wsg_at EQUAL -1)
    message(FATAL_ERROR "${WSG_PKG_SRC}/${wsg_name} has no line "
                        "'${wsg_exec}' to write this install's paths into")
  endif()
  string(REPLACE "${wsg_exec}"
    "ExecStart=${wsg_bindir}/wsgemu --config ${wsg_confdir}/${wsg_conf}"
    wsg_unit "${wsg_unit}")
  file(WRITE "${WSG_PKG_BIN}/${wsg_name}" "${wsg_unit}")
  file(INSTALL DESTINATION "${wsg_unitdir}" TYPE FILE
       FILES "${WSG_PKG_BIN}/${wsg_name}")
endforeach()
