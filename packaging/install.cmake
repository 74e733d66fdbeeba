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
# SYSCONFDIR follows GNUInstallDirs' rule for a relative one: /etc for the
# prefixes / and /usr, /etc/opt/X for /opt/X, else PREFIX/etc. DESTDIR
# (CPack's staging directory) is applied by file(INSTALL) as usual, and is
# not part of any path written into the unit.

# An absolute directory as it is, a relative one below the prefix.
function(wsg_full_dir out dir)
  if(IS_ABSOLUTE "${dir}")
    set(${out} "${dir}" PARENT_SCOPE)
  else()
    set(${out} "${CMAKE_INSTALL_PREFIX}/${dir}" PARENT_SCOPE)
  endif()
endfunction()

string(REGEX REPLACE "/+$" "" wsg_prefix "${CMAKE_INSTALL_PREFIX}")
if(IS_ABSOLUTE "${WSG_SYSCONFDIR}")
  set(wsg_etc "${WSG_SYSCONFDIR}")
elseif(wsg_prefix STREQUAL "" OR wsg_prefix STREQUAL "/usr")
  set(wsg_etc "/${WSG_SYSCONFDIR}")
elseif(wsg_prefix MATCHES "^/opt/(.+)$")
  set(wsg_etc "/${WSG_SYSCONFDIR}/opt/${CMAKE_MATCH_1}")
else()
  set(wsg_etc "${wsg_prefix}/${WSG_SYSCONFDIR}")
endif()
set(wsg_confdir "${wsg_etc}/wsgemu")
wsg_full_dir(wsg_bindir "${WSG_BINDIR}")
wsg_full_dir(wsg_unitdir "${WSG_UNITDIR}")

# The config file: never overwrite one that is there (the Debian package
# marks it a conffile, so dpkg asks instead).
if(EXISTS "$ENV{DESTDIR}${wsg_confdir}/wsgemu.conf")
  message(STATUS
    "Keeping: $ENV{DESTDIR}${wsg_confdir}/wsgemu.conf (the example is in the doc directory)")
else()
  file(INSTALL DESTINATION "${wsg_confdir}" TYPE FILE
       FILES "${WSG_PKG_SRC}/wsgemu.conf")
endif()

# The unit: the source names the Debian paths; write this install's.
set(wsg_exec "ExecStart=/usr/bin/wsgemu --config /etc/wsgemu/wsgemu.conf")
file(READ "${WSG_PKG_SRC}/wsgemu.service" wsg_unit)
string(FIND "${wsg_unit}" "${wsg_exec}" wsg_at)
if(wsg_at EQUAL -1)
  message(FATAL_ERROR "${WSG_PKG_SRC}/wsgemu.service has no line "
                      "'${wsg_exec}' to write this install's paths into")
endif()
string(REPLACE "${wsg_exec}"
  "ExecStart=${wsg_bindir}/wsgemu --config ${wsg_confdir}/wsgemu.conf"
  wsg_unit "${wsg_unit}")
file(MAKE_DIRECTORY "${WSG_PKG_BIN}")
file(WRITE "${WSG_PKG_BIN}/wsgemu.service" "${wsg_unit}")
file(INSTALL DESTINATION "${wsg_unitdir}" TYPE FILE
     FILES "${WSG_PKG_BIN}/wsgemu.service")
