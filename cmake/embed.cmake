# cmake -DOUT=FILE.c -DBASE=DIR -DFILES="a;b;..." -P embed.cmake
# Writes FILE.c with each of FILES (paths under BASE) as a byte array and
# the table wsg_web_assets (src/daemon/web/assets.h) that names them by
# URL path ("/index.html") with their Content-Type. Bytes, not a string
# literal: C99 promises string literals of 4095 bytes only, and a page is
# longer.
set(types_html "text/html; charset=utf-8")
set(types_js "text/javascript; charset=utf-8")
set(types_css "text/css; charset=utf-8")
set(types_svg "image/svg+xml")
set(types_ico "image/x-icon")

set(body "")
set(table "")
set(i 0)
foreach(f IN LISTS FILES)
  file(RELATIVE_PATH rel ${BASE} ${f})
  get_filename_component(ext ${f} LAST_EXT)
  string(SUBSTRING "${ext}" 1 -1 ext)
  if(NOT DEFINED types_${ext})
    message(FATAL_ERROR "embed.cmake: no Content-Type for ${rel}")
  endif()
  file(READ ${f} hex HEX)
  string(LENGTH "${hex}" n)
  math(EXPR n "${n} / 2")
  if(n EQUAL 0)
    message(FATAL_ERROR "embed.cmake: ${rel} is empty")
  endif()
  # 16 bytes a line.
  string(REGEX REPLACE "([0-9a-f][0-9a-f])" "0x\\1," hex "${hex}")
  string(REGEX REPLACE "((0x..,){16})" "\\1\n    " hex "${hex}")
  string(APPEND body
    "/* ${rel} */\nstatic const unsigned char asset_${i}[] = {\n    ${hex}};\n\n")
  string(APPEND table
    "    {\"/${rel}\", \"${types_${ext}}\", asset_${i}, ${n}u},\n")
  math(EXPR i "${i} + 1")
endforeach()

file(WRITE ${OUT}.tmp
"/* Generated from web/ by cmake/embed.cmake at build time: do not edit. */
#include \"web/assets.h\"

${body}const struct wsg_web_asset wsg_web_assets[] = {
${table}    {NULL, NULL, NULL, 0}};
")
# Only a changed file is rewritten: no rebuild of the daemon otherwise.
execute_process(COMMAND ${CMAKE_COMMAND} -E copy_if_different ${OUT}.tmp
                        ${OUT})
file(REMOVE ${OUT}.tmp)
