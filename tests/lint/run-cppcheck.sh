#!/usr/bin/env bash
# run-cppcheck.sh SOURCE_DIR: cppcheck's warning, performance and portability checks over the
# project, clean or failing. The sources every configuration of their macros; the tests with
# GoogleTest's macros known (the typed-test ones spelled out, which its library lacks) and the
# one definition they cannot do without. Eigen's headers are left out: checking them is
# Eigen's business and would take most of the time. Findings that are the tool's mistake are
# silenced in place (cppcheck-suppress) with the reason.
set -euo pipefail
cd "$1"
common=(--enable=warning,performance,portability --std=c++17 --inline-suppr --quiet -j 2
        --error-exitcode=1 --template='{file}:{line}: {severity} {id}: {message}'
        -I common/include -I host/include -I host/dds/include -I firmware/app
        -I firmware/boards/linux -I hil/forearm -I hil/joint_bench)
cppcheck "${common[@]}" common firmware host hil
cppcheck "${common[@]}" --library=googletest "-DTYPED_TEST(s,n)=void s##_##n()" \
         "-DTYPED_TEST_SUITE(...)=" '-DHMPC_FOREARM_DBC="dbc"' '-DHMPC_JOINT_DBC="dbc"' \
         '-DHMPC_JOINT_BOARD_PROGRAM="board"' '-DHMPC_JOINT_BENCH_PROGRAM="bench"' tests
echo "cppcheck: common, firmware, host, hil and tests clean"
