#!/usr/bin/env bash
# The sanitizer job (docs/hardening.md#sanitizers). Two scopes:
#
#   scripts/sanitize_ci.sh [asan|tsan ...]          the CI scope: the readers' tests under
#                                                   AddressSanitizer + UndefinedBehaviorSanitizer
#                                                   (`asan`, which .ci/run runs after the README's
#                                                   test command) and the tests of the parallel
#                                                   loops (core, normals, filters, segmentation,
#                                                   features, simulator, perceive, part-graph
#                                                   training, kitchen room structure and
#                                                   fixtures) under ThreadSanitizer (`tsan`)
#   scripts/sanitize_ci.sh --full [asan|tsan ...]   every unit test under ASan + UBSan and also
#                                                   perceive's stage tests and the executive's
#                                                   under TSan; about an hour cold on two cores
#
# Builds: build-asan/ (-DMULTICUE_SANITIZE=address,undefined) and build-tsan/
# (-DMULTICUE_SANITIZE=thread), -O1 -g1 with g++, without benchmarks, accuracy drivers,
# examples, the Python module, the PCL/Open3D tests and the report viewer; ccache makes a second
# run cheap. Tests that need the shared scans are skipped (MULTICUE_SHARED_DATA_DIR points
# nowhere) to keep the time bounded. Any sanitizer report fails the job.
set -euo pipefail
cd "$(dirname "$0")/.."

full=0
if [[ "${1:-}" == "--full" ]]; then
    full=1
    shift
fi
stages=("$@")
if [[ ${#stages[@]} -eq 0 ]]; then stages=(asan tsan); fi

# The CI scope: the readers (PCD, PLY, OBJ, configuration, PointCloud2, ROS bags, URDF, datasets
# and classifier files) and the core, search, filters and normals code under ASan + UBSan (the
# readers of part-graph models, the object database and tasks need the whole library built with
# ASan, 15 minutes more: --full); under TSan the parallel loops of the
# core, of perceive's stages (normals, filters, region growing and part segmentation, sample
# consensus, part features), of the simulator, of perceive itself (objects categorised and
# modelled in parallel, batches of frames), of part-graph training and of the kitchen map's room
# structure and fixtures.
ci_asan_tests=(test_core test_pcd test_config test_ply_obj test_point_cloud2 test_ros_bags test_urdf
               test_search test_filters test_normals test_ml)
ci_tsan_tests=(test_core test_normals test_filters test_clustering test_convexity_split
               test_sample_consensus test_features test_sim test_perceive
               test_part_graph_training test_kitchen_fixtures)
# Part-graph training runs 20 times slower under TSan (215 s for its four tests): the CI scope runs
# the two that train on several threads, turntable views and perceived table scenes.
declare -A ci_tsan_filter=(
    [test_part_graph_training]="PartGraphTraining.DeterministicAcrossThreads:PartGraphTraining.TableScenesAddPerceivedObjects"
    [test_kitchen_fixtures]="RoomStructure.TheSameOnAnyThreadCount:Fixtures.TheSameOnAnyThreadCount")

common=(-G Ninja -DCMAKE_BUILD_TYPE=RelWithDebInfo -DCMAKE_CXX_FLAGS_RELWITHDEBINFO="-O1 -g1"
        -DMULTICUE_BUILD_BENCH=OFF -DMULTICUE_BUILD_EVAL=OFF -DMULTICUE_BUILD_EXAMPLES=OFF
        -DMULTICUE_BUILD_PYTHON=OFF -DMULTICUE_INSTALL=OFF -DMULTICUE_PCL_TESTS=OFF
        -DMULTICUE_OPEN3D_TESTS=OFF -DMULTICUE_REPORT_VIEWER=OFF
        -DMULTICUE_SHARED_DATA_DIR="$PWD/build-no-shared-data")

supp="$PWD/scripts/sanitizers"
export ASAN_OPTIONS="detect_leaks=1:abort_on_error=1:detect_stack_use_after_return=0"
export LSAN_OPTIONS="suppressions=$supp/lsan.supp"
export UBSAN_OPTIONS="print_stacktrace=1:halt_on_error=1"
export TSAN_OPTIONS="halt_on_error=1:second_deadlock_stack=1:suppressions=$supp/tsan.supp"

seconds() { date +%s; }

for stage in "${stages[@]}"; do
    start=$(seconds)
    case "$stage" in
        asan)
            cmake -S . -B build-asan "${common[@]}" -DMULTICUE_SANITIZE=address,undefined
            if [[ $full -eq 1 ]]; then
                cmake --build build-asan -j2
                built=$(seconds)
                # The browser test drives Chromium over the CLI (minutes under ASan, and Chromium
                # is not ours); the documentation checks do not run multicue code.
                ctest --test-dir build-asan --output-on-failure -j2 -E '^(report_browser|docs_)'
            else
                cmake --build build-asan -j2 --target "${ci_asan_tests[@]}"
                built=$(seconds)
                for t in "${ci_asan_tests[@]}"; do
                    echo "sanitize_ci.sh: $t under AddressSanitizer + UndefinedBehaviorSanitizer"
                    "build-asan/tests/$t" --gtest_brief=1
                done
            fi
            ;;
        tsan)
            tests=("${ci_tsan_tests[@]}")
            if [[ $full -eq 1 ]]; then
                tests=("${ci_tsan_tests[@]}" test_perceive_stages test_executive)
            fi
            cmake -S . -B build-tsan "${common[@]}" -DMULTICUE_SANITIZE=thread
            cmake --build build-tsan -j2 --target "${tests[@]}"
            built=$(seconds)
            for t in "${tests[@]}"; do
                echo "sanitize_ci.sh: $t under ThreadSanitizer"
                filter="*"
                if [[ $full -eq 0 && -n "${ci_tsan_filter[$t]:-}" ]]; then
                    filter="${ci_tsan_filter[$t]}"
                fi
                "build-tsan/tests/$t" --gtest_brief=1 --gtest_filter="$filter"
            done
            ;;
        *)
            echo "sanitize_ci.sh: unknown stage '$stage' (asan, tsan)" >&2
            exit 2
            ;;
    esac
    end=$(seconds)
    echo "sanitize_ci.sh: $stage: build $((built - start)) s, tests $((end - built)) s"
done
