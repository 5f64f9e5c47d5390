# cmake -DFILE=F -DPATTERN=REGEX -P file_contains.cmake: fails unless FILE holds a match of REGEX
# (CLI tests of files that a command wrote).
if(NOT EXISTS "${FILE}")
  message(FATAL_ERROR "missing ${FILE}")
endif()
file(READ "${FILE}" _content)
string(REGEX MATCH "${PATTERN}" _match "${_content}")
if(_match STREQUAL "")
  message(FATAL_ERROR "${FILE} does not match ${PATTERN}")
endif()
