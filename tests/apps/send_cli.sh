#!/usr/bin/env bash
# CLI tests of `rowloc send` against a real `rowloc serve` (tests/apps/send_cli.cmake).
#
#   send_cli.sh ROWLOC SRC WORK equals-replay
#       simulates vineyard-002-4us, cuts its log to the first 20000 messages, serves the run's row
#       map as "vineyard-002", and requires `rowloc send` to write the same bytes as `rowloc replay`:
#       with the default filter, with --filter canopy-gnss-flat (a name on the server), and with the
#       vehicle and filter given as files (sent inline); then the same for a log with a 2 MiB line and
#       an unterminated last line, which both refuse (logged with their line numbers).
#   send_cli.sh ROWLOC SRC WORK expect STATUS REGEX ARGS...
#       runs `rowloc ARGS...` and requires exit STATUS and output matching REGEX (grep -E). When an
#       argument holds @SERVER@, a server is started first and @SERVER@ becomes its HOST:PORT;
#       @WORK@ becomes WORK.
#
# Every server started here listens on a free loopback port (--port 0, read from its first stdout
# line) and is stopped with SIGTERM (exit 0 required), SIGKILL after 10 s.
set -u -o pipefail

ROWLOC=$1 SRC=$2 WORK=$3 MODE=$4
shift 4
SERVER_PID=""
SERVER_ADDR=""

fail() {
  echo "FAIL: $*" >&2
  exit 1
}

cleanup() {
  if [[ -n $SERVER_PID ]] && kill -0 "$SERVER_PID" 2>/dev/null; then
    kill -KILL "$SERVER_PID" 2>/dev/null
    wait "$SERVER_PID" 2>/dev/null
  fi
}
trap cleanup EXIT

# start_server MAPS_DIR: sets SERVER_PID and SERVER_ADDR.
start_server() {
  "$ROWLOC" serve --port 0 --vehicles "$SRC/config/vehicles" --maps "$1" --filters "$SRC/config/filters" \
    >"$WORK/serve.out" 2>"$WORK/serve.err" </dev/null &
  SERVER_PID=$!
  local line="" i
  for ((i = 0; i < 300; ++i)); do
    line=$(head -n 1 "$WORK/serve.out")
    [[ $line == '{"type":"listening"'*'}' ]] && break
    kill -0 "$SERVER_PID" 2>/dev/null || fail "rowloc serve ended before listening: $(tail -n 20 "$WORK/serve.err")"
    sleep 0.1
  done
  SERVER_ADDR=$(sed -n 's/.*"tcp":"\([^"]*\)".*/\1/p' <<<"$line")
  [[ $SERVER_ADDR == 127.0.0.1:* ]] || fail "no listening line in 30 s: '$line'"
  echo "rowloc serve listens on $SERVER_ADDR"
}

stop_server() {
  local i status
  kill -TERM "$SERVER_PID"
  for ((i = 0; i < 100; ++i)); do
    kill -0 "$SERVER_PID" 2>/dev/null || break
    sleep 0.1
  done
  kill -0 "$SERVER_PID" 2>/dev/null && kill -KILL "$SERVER_PID"
  wait "$SERVER_PID"
  status=$?
  SERVER_PID=""
  [[ $status == 0 ]] || fail "rowloc serve exited with $status after SIGTERM: $(tail -n 20 "$WORK/serve.err")"
}

rm -rf "$WORK"
mkdir -p "$WORK"
cd "$WORK" || exit 1

case $MODE in
equals-replay)
  "$ROWLOC" simulate "$SRC/config/scenarios/vineyard-002-4us.json" -o sim --no-baselines >simulate.log 2>&1 ||
    fail "rowloc simulate: $(tail -n 20 simulate.log)"
  head -n 20001 sim/sensors.ndjson >log.ndjson
  rm -f sim/sensors.ndjson sim/truth.ndjson
  mkdir -p maps
  cp sim/row-map.geojson maps/vineyard-002.geojson
  start_server maps
  vehicle=$SRC/config/vehicles/vineyard-ugv-4ws.json
  filter=$SRC/config/filters/canopy-gnss-flat.json
  # name: send options | replay options
  runs=(
    "default|--vehicle vineyard-ugv-4ws|"
    "filter-by-name|--vehicle vineyard-ugv-4ws --filter canopy-gnss-flat|--filter $filter"
    "inline-configs|--vehicle $vehicle --filter $filter|--filter $filter"
  )
  for run in "${runs[@]}"; do
    IFS='|' read -r name send_options replay_options <<<"$run"
    # shellcheck disable=SC2086  # the options are words
    "$ROWLOC" send log.ndjson --to "$SERVER_ADDR" $send_options --map vineyard-002 -o "send-$name.ndjson" \
      >"send-$name.log" 2>&1 || fail "rowloc send ($name): $(tail -n 20 "send-$name.log")"
    # shellcheck disable=SC2086
    "$ROWLOC" replay log.ndjson --vehicle "$vehicle" $replay_options --map sim/row-map.geojson \
      -o "replay-$name.ndjson" >"replay-$name.log" 2>&1 || fail "rowloc replay ($name): $(tail -n 20 "replay-$name.log")"
    grep -q '"type":"update","t":[0-9.]*,"sensor":"ultrasonic"' "replay-$name.ndjson" ||
      fail "$name: the replay used no echo: not a test of the map"
    cmp "send-$name.ndjson" "replay-$name.ndjson" || fail "$name: rowloc send and rowloc replay differ"
    echo "$name: $(wc -l <"send-$name.ndjson") lines, the same bytes ($(tail -n 1 "send-$name.log" | sed 's/.*\] //'))"
  done
  cmp -s send-default.ndjson send-filter-by-name.ndjson && fail "the filter made no difference"
  # Lines the log reader refuses (issue 26): a 2 MiB line (line 1001) and an unterminated last line.
  # send refuses them as replay does (logged with their numbers, not sent) and writes the same bytes.
  {
    head -n 1000 log.ndjson
    printf '{"type":"imu","t":0,"padding":"%s"}\n' "$(head -c 2097152 /dev/zero | tr '\0' x)"
    tail -n +1001 log.ndjson | head -c -1
  } >refused.ndjson
  "$ROWLOC" send refused.ndjson --to "$SERVER_ADDR" --vehicle vineyard-ugv-4ws --map vineyard-002 \
    -o send-refused.ndjson >send-refused.log 2>&1 || fail "rowloc send (refused): $(tail -n 20 send-refused.log)"
  "$ROWLOC" replay refused.ndjson --vehicle "$vehicle" --map sim/row-map.geojson -o replay-refused.ndjson \
    >replay-refused.log 2>&1 || fail "rowloc replay (refused): $(tail -n 20 replay-refused.log)"
  for tool in send replay; do
    grep -q "refused.ndjson:1001: rejected: line: longer than 1 MiB (1048576 bytes" "$tool-refused.log" ||
      fail "$tool did not refuse line 1001: $(tail -n 20 "$tool-refused.log")"
    grep -q "refused.ndjson:20002: rejected: line: not terminated by a newline" "$tool-refused.log" ||
      fail "$tool did not refuse the unterminated last line: $(tail -n 20 "$tool-refused.log")"
  done
  cmp send-refused.ndjson replay-refused.ndjson || fail "refused lines: rowloc send and rowloc replay differ"
  echo "refused lines: $(wc -l <send-refused.ndjson) lines, the same bytes"
  stop_server
  ;;
expect)
  expected_status=$1 regex=$2
  shift 2
  args=()
  for arg in "$@"; do
    if [[ $arg == *@SERVER@* && -z $SERVER_PID ]]; then start_server "$SRC/maps"; fi
    arg=${arg//@SERVER@/$SERVER_ADDR}
    args+=("${arg//@WORK@/$WORK}")
  done
  echo "rowloc ${args[*]}"
  output=$("$ROWLOC" "${args[@]}" 2>&1)
  status=$?
  echo "$output"
  [[ $status == "$expected_status" ]] || fail "expected exit $expected_status, got $status"
  grep -Eq -- "$regex" <<<"$output" || fail "output does not match: $regex"
  if [[ -n $SERVER_PID ]]; then stop_server; fi
  ;;
*)
  fail "unknown mode '$MODE'"
  ;;
esac
echo "PASS"
