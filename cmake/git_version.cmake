# Run at build time (cmake -P): writes OUT with the source tree's `git describe`, only when it
# changed, so results.json names the code that produced it.
execute_process(COMMAND git -C "${SRC}" describe --always --dirty --tags
  OUTPUT_VARIABLE _describe OUTPUT_STRIP_TRAILING_WHITESPACE ERROR_QUIET RESULT_VARIABLE _rc)
if(NOT _rc EQUAL 0 OR _describe STREQUAL "")
  set(_describe "unknown")
endif()
set(_text "#pragma once\n#define COLORFREE_GIT_DESCRIBE \"${VERSION}-${_describe}\"\n")
if(EXISTS "${OUT}")
  file(READ "${OUT}" _old)
endif()
if(NOT "${_old}" STREQUAL "${_text}")
  file(WRITE "${OUT}" "${_text}")
endif()
