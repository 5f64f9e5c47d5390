# Runs a command that names one of its inputs as an output and checks that it is refused and that
# the input is untouched (issue 26, "files destroyed — never").
#   cmake -DORIGINAL=file -DCOPY=file -DCOMMAND="prog;arg;..." -DEXPECT_OUTPUT=regex
#         [-DEXPECT_STATUS=2] [-DLINK=path] -P keeps_input.cmake
# COPY is made a fresh copy of ORIGINAL first; with LINK, LINK is made a symbolic link to COPY.
file(COPY_FILE ${ORIGINAL} ${COPY})
if(DEFINED LINK)
  file(REMOVE ${LINK})
  file(CREATE_LINK ${COPY} ${LINK} SYMBOLIC)
endif()
execute_process(COMMAND ${COMMAND} RESULT_VARIABLE status OUTPUT_VARIABLE out ERROR_VARIABLE err)
message("${out}${err}")
if(NOT DEFINED EXPECT_STATUS)
  set(EXPECT_STATUS 2)
endif()
if(NOT status EQUAL EXPECT_STATUS)
  message(FATAL_ERROR "expected exit status ${EXPECT_STATUS}, got ${status}")
endif()
if(NOT "${err}" MATCHES "${EXPECT_OUTPUT}")
  message(FATAL_ERROR "stderr does not match: ${EXPECT_OUTPUT}")
endif()
execute_process(COMMAND ${CMAKE_COMMAND} -E compare_files ${ORIGINAL} ${COPY} RESULT_VARIABLE differ)
if(NOT differ EQUAL 0)
  message(FATAL_ERROR "the input ${COPY} was changed")
endif()
