# CLI tests of 'rowloc send' (docs/service.md): the estimate stream it reads back from a running
# 'rowloc serve' is 'rowloc replay's output byte for byte, and bad input ends it with exit 2 and a
# message that names the problem. tests/apps/send_cli.sh starts each server on a free loopback port
# and stops it (the C++ client's tests and send's exit 1 when the service goes away are in
# tests/service/client_server_test.cpp).
set(_send_out ${CMAKE_CURRENT_BINARY_DIR}/send)
set(_send_log ${PROJECT_SOURCE_DIR}/tests/data/logs/vineyard-002-1us-echoes.ndjson)
# rowloc_send_test(NAME MODE ARGS...): send_cli.sh MODE ARGS... in its own directory.
function(rowloc_send_test name)
  add_test(NAME apps.${name}
           COMMAND bash ${CMAKE_CURRENT_SOURCE_DIR}/apps/send_cli.sh $<TARGET_FILE:rowloc> ${PROJECT_SOURCE_DIR}
                   ${_send_out}/${name} ${ARGN})
  set_tests_properties(apps.${name} PROPERTIES LABELS apps TIMEOUT 300)
endfunction()

rowloc_send_test(send_equals_replay equals-replay)
rowloc_send_test(send_rejects_missing_log expect 2 "log .no-such-log\\.ndjson.: no such file"
                 send no-such-log.ndjson --to @SERVER@ --vehicle vineyard-ugv-4ws -o @WORK@/x.ndjson)
# Port 1 on the loopback: nothing listens there.
rowloc_send_test(send_rejects_unreachable_service expect 2 "send: cannot connect to 127\\.0\\.0\\.1:1: "
                 send ${_send_log} --to 127.0.0.1:1 --vehicle vineyard-ugv-4ws -o @WORK@/x.ndjson)
rowloc_send_test(send_rejects_unknown_vehicle expect 2 "send: unknown_vehicle: vehicle 'no-such-ugv'"
                 send ${_send_log} --to @SERVER@ --vehicle no-such-ugv -o @WORK@/x.ndjson)
rowloc_send_test(send_rejects_bad_rate expect 2 "--rate: expected max, realtime or xN \\(N > 0\\), got 'x0'"
                 send ${_send_log} --to @SERVER@ --vehicle vineyard-ugv-4ws --rate x0 -o @WORK@/x.ndjson)
rowloc_send_test(send_rejects_bad_address expect 2 "address 'localhost': expected HOST:PORT or unix:PATH"
                 send ${_send_log} --to localhost --vehicle vineyard-ugv-4ws -o @WORK@/x.ndjson)
