#!/usr/bin/env bash
# multicue_node against a real ROS master:
#   1. frames (mOSD, else simulated) are written into a ROS 1 bag (librosbag), 2 s apart;
#   2. `multicue perceive --bag` perceives the bag: the reference;
#   3. roscore on a free port, multicue_node, a collector; `rosbag play` plays the bag;
#   4. every labelled cloud, marker set and result the node published equals the reference;
#   5. bad clouds (no x/y/z, truncated data) are skipped; the task service enumerates the newest
#      frame; a bad ~config parameter is refused by name;
#   6. frames published faster than the node perceives them: it drops, it does not lag.
# Rates are printed, not asserted. Everything started here is stopped on exit, also on failure.
# usage: node_test.sh BUILD_DIR SHARED_DATA_DIR
set -euo pipefail
build=$1
shared=$2
frames_n=${MULTICUE_ROS_TEST_FRAMES:-3}
topic=/camera/depth_registered/points
work=$(mktemp -d "${TMPDIR:-/tmp}/multicue-ros-test.XXXXXX")
pids=()

cleanup() {
    local rc=$?
    # The watchdog's sleep too: a left-over child holding the output keeps ctest waiting.
    if [[ -n ${watchdog:-} ]]; then
        pkill -P "$watchdog" 2>/dev/null || true
        kill "$watchdog" 2>/dev/null || true
    fi
    for pid in "${pids[@]}"; do
        # Each process was started in its own session: stop its whole group.
        kill -INT -- "-$pid" 2>/dev/null || true
    done
    sleep 1
    for pid in "${pids[@]}"; do
        kill -KILL -- "-$pid" 2>/dev/null || true
    done
    if [[ $rc -ne 0 ]]; then
        echo "--- node log (failure) ---"
        tail -n 40 "$work/node.log" 2>/dev/null || true
    fi
    rm -rf "$work"
    exit $rc
}
trap cleanup EXIT
trap "exit 143" INT TERM
# Stop on our own before ctest's timeout (300 s) would kill this script without its cleanup.
( sleep "${MULTICUE_ROS_TEST_LIMIT:-240}"; echo "node_test: time limit reached"; kill -TERM $$ ) &
watchdog=$!

start() {  # start LOG CMD...: in its own session, so that cleanup stops its children too
    local log=$1
    shift
    setsid "$@" >"$log" 2>&1 &
    pids+=($!)
}

# A free port for this test's master, so that parallel runs never share one.
port=$(/usr/bin/python3 -c 'import socket; s=socket.socket(); s.bind(("127.0.0.1",0)); print(s.getsockname()[1])')
export ROS_MASTER_URI=http://127.0.0.1:$port
export ROS_IP=127.0.0.1
export ROS_HOME=$work/ros
export ROS_LOG_DIR=$work/ros/log
unset ROS_HOSTNAME

echo "== frames and bag"
"$build/tests/ros/ros_test_data" frames "$work/frames" "$frames_n" "$shared"
"$build/tests/ros/ros_test_tool" write-bag "$work/frames" "$work/test.bag" "$topic" 2.0
"$build/multicue" perceive --no-report -q --bag "$work/test.bag" --topic "$topic" --out "$work/cli"

echo "== roscore on port $port"
start "$work/roscore.log" roscore -p "$port"
ready=0
for _ in $(seq 100); do
    if rostopic list >/dev/null 2>&1; then ready=1; break; fi
    sleep 0.2
done
[[ $ready -eq 1 ]] || { echo "roscore did not come up"; exit 1; }

echo "== multicue_node (roslaunch multicue multicue.launch)"
export ROS_PACKAGE_PATH=$build/ros
start "$work/node.log" roslaunch multicue multicue.launch "points:=$topic" stats_period:=0.5 threads:=2
ready=0
for _ in $(seq 150); do
    if rosservice list 2>/dev/null | grep -q /multicue_node/run_task; then ready=1; break; fi
    sleep 0.2
done
[[ $ready -eq 1 ]] || { echo "multicue_node did not come up"; exit 1; }

echo "== play the bag (frames 2 s apart)"
start "$work/collect.log" "$build/tests/ros/ros_test_tool" collect "$work/got" "$frames_n" 120
for _ in $(seq 100); do [[ -f $work/got/ready ]] && break; sleep 0.1; done
sleep 1
rosbag play -q "$work/test.bag"
collector=${pids[-1]}
for _ in $(seq 600); do kill -0 "$collector" 2>/dev/null || break; sleep 0.2; done
cat "$work/collect.log"
echo "node stats: $(cat "$work/got/stats.json")"
"$build/tests/ros/ros_test_data" compare "$work/cli" "$work/got" 1

echo "== bad clouds are skipped, the node goes on"
"$build/tests/ros/ros_test_tool" publish-bad "$topic"
sleep 1
start "$work/collect_bad.log" "$build/tests/ros/ros_test_tool" collect "$work/got_bad" 1000000 1.5
collector=${pids[-1]}
for _ in $(seq 100); do kill -0 "$collector" 2>/dev/null || break; sleep 0.1; done
/usr/bin/python3 -c '
import json, sys
s = json.load(open(sys.argv[1]))
assert s["failed"] == 2, s
print("skipped", s["failed"], "bad clouds:", s)' "$work/got_bad/stats.json"
grep -o "frame skipped: .*" "$work/node.log" | head -2

echo "== task service"
task=$("$build/tests/ros/ros_test_tool" call-task '{"task": "enumerate", "learn": false}')
echo "$task" | head -c 300; echo
echo "$task" | /usr/bin/python3 -c '
import json, sys
r = json.load(sys.stdin)
assert r["ok"], r["result"]
report = json.loads(r["result"])
assert len(report["hypotheses"]) > 0, "no hypotheses"
print("run_task enumerate:", len(report["hypotheses"]), "hypotheses,", report["methods"])'
bad=$("$build/tests/ros/ros_test_tool" call-task '{"task": "fly"}')
echo "$bad" | grep -q '"ok":false' || { echo "a bad task was not refused: $bad"; exit 1; }

rate_phase() {  # rate_phase HZ REPEAT: publish the frames, report what the node did
    local hz=$1 repeat=$2 n=$3
    local before after published
    before=$(cat "$work/stats.json")
    published=$("$build/tests/ros/ros_test_tool" publish "$work/frames" "$topic" "$hz" "$repeat")
    sleep 2
    start "$work/collect$n.log" "$build/tests/ros/ros_test_tool" collect "$work/got$n" 1000000 1.5
    local collector=${pids[-1]}
    for _ in $(seq 100); do kill -0 "$collector" 2>/dev/null || break; sleep 0.1; done
    cp "$work/got$n/stats.json" "$work/stats.json"
    after=$(cat "$work/stats.json")
    /usr/bin/python3 - "$before" "$after" "$published" "$hz" <<'EOF2'
import json, sys
a, b = json.loads(sys.argv[1]), json.loads(sys.argv[2])
seconds = float(sys.argv[3].split(" in ")[1].split(" s")[0])
received = b["received"] - a["received"]
processed = b["processed"] - a["processed"]
dropped = b["dropped"] - a["dropped"]
print(f"published at {sys.argv[4]} Hz: {received} frames in ({received / seconds:.1f} Hz), "
      f"{processed} perceived ({processed / (seconds + b['frame_ms'] / 1000):.1f} Hz), "
      f"{dropped} dropped; last frame {b['frame_ms']:.0f} ms, its result "
      f"{b['latency_ms']:.0f} ms after it arrived")
assert b["received"] == b["processed"] + b["dropped"] + b["failed"], "frames unaccounted for"
assert processed >= 1, "nothing perceived"
EOF2
}
cp "$work/got_bad/stats.json" "$work/stats.json"
echo "== the configuration from ROS parameters: an unknown key is refused by name"
bad_config() {  # bad_config NAME ARGS...: the node must exit 2 naming support.bogus_key
    local name=$1
    shift
    set +e
    timeout 60 "$build/multicue_node" "__name:=$name" "$@" >"$work/$name.log" 2>&1
    local rc=$?
    set -e
    grep -q "support.bogus_key" "$work/$name.log" && [[ $rc -eq 2 ]] ||
        { echo "a bad ~config was not refused (exit $rc):"; cat "$work/$name.log"; exit 1; }
    echo "refused: $(grep -o 'multicue_node: .*' "$work/$name.log" | head -1)"
}
rosparam set /bad_struct/config "{support: {bogus_key: 1}, threads: 1}"
bad_config bad_struct
bad_config bad_text '_config:={"support": {"bogus_key": 1}}'

echo "== at 2 Hz, then faster than the node (20 Hz): it drops frames, it does not lag"
rate_phase 2 2 2
rate_phase 20 5 3
echo "node_test: passed"
