# door_state_recognition: one-command set-up.
#   make demo   install what is missing, build, simulate a scene, show the result
#   make test   install what is missing, build, run every test
# Also: make build, make bench, make eval (the README's accuracy sweeps),
# make eval-drive (door states fused over simulated drives),
# make clean, make sanitize (ASan+UBSan tests, part of make test), make fuzz
# (libFuzzer targets, FUZZ_SECONDS each).
SHELL := /bin/bash
REPO  := $(abspath $(dir $(lastword $(MAKEFILE_LIST))))
# BUILD may be moved (make build BUILD=/tmp/other) to keep a second workspace
# apart, e.g. for a second person building at the same time.
BUILD ?= $(REPO)/build
WS    := $(BUILD)/.ws
BIN   := $(BUILD)/bin
export DSR_BUILD := $(BUILD)
JOBS  ?= 2
# Debian's ROS lives in /usr; a second python3 (pyenv) on PATH lacks the ROS
# Python modules, so /usr/bin goes first for catkin, rostest and roslaunch.
export PATH := /usr/bin:$(PATH)
CATKIN_ARGS := -DCMAKE_BUILD_TYPE=Release -DPYTHON_EXECUTABLE=/usr/bin/python3 \
               -DPython3_EXECUTABLE=/usr/bin/python3 -DCATKIN_ENABLE_TESTING=ON

.PHONY: deps build test demo bench eval clean rviz-shot gallery sanitize fuzz
FUZZ_SECONDS ?= 60

deps:
	@$(REPO)/scripts/install_deps.sh

build: deps
	@mkdir -p $(WS)/src
	@ln -sfn $(REPO) $(WS)/src/door_state_recognition
	@cd $(WS) && catkin_make -j$(JOBS) $(CATKIN_ARGS) >$(BUILD)/catkin_make.log 2>&1 \
	  || { tail -n 60 $(BUILD)/catkin_make.log; echo "build failed: full log in build/catkin_make.log"; exit 1; }
	@mkdir -p $(BIN)
	@for exe in $(WS)/devel/lib/door_state_recognition/*; do \
	  case "$$(basename $$exe)" in test_*) continue;; esac; [ -x "$$exe" ] && [ -f "$$exe" ] && ln -sfn "$$exe" $(BIN)/$$(basename $$exe); done; true
	@echo "built: executables in build/bin/ ($$(ls $(BIN) | tr '\n' ' '))"

test: build
	@rm -rf $(WS)/build/test_results
	@cd $(WS) && source devel/setup.bash && \
	  catkin_make -j$(JOBS) $(CATKIN_ARGS) tests >$(BUILD)/run_tests.log 2>&1 || { tail -n 40 $(BUILD)/run_tests.log; exit 1; }; \
	  catkin_make -j1 $(CATKIN_ARGS) run_tests >>$(BUILD)/run_tests.log 2>&1; \
	  grep -E "^\[  (PASSED|FAILED)  \]|^\[==========\] .* ran|Failure|rostest|FAILURE" $(BUILD)/run_tests.log | tail -n 60; \
	  catkin_test_results build/test_results | tail -n 1; \
	  /usr/bin/python3 $(REPO)/scripts/test_summary.py build/test_results
	@$(REPO)/test/sanitize/run.sh $(BUILD)/asan $(JOBS)

# The ROS-free core, simulator and their gtest tests built with AddressSanitizer
# + UndefinedBehaviorSanitizer (gcc) in $(BUILD)/asan and run; any report fails.
sanitize: deps
	@$(REPO)/test/sanitize/run.sh $(BUILD)/asan $(JOBS)

# libFuzzer targets (clang 14) built in $(BUILD)/fuzz, each run FUZZ_SECONDS
# from the seed corpus fuzz/corpus/; fails on any crash.
fuzz: deps
	@JOBS=$(JOBS) $(REPO)/fuzz/run.sh $(BUILD)/fuzz $(FUZZ_SECONDS)

demo: build
	@$(REPO)/scripts/demo.sh

bench: build
	@$(REPO)/scripts/bench.sh

# The accuracy sweeps of the README's table (EVAL_SWEEPS="tls-400k-1000 ..."
# picks some); per-seed lines in $(BUILD)/eval/.
eval: build
	@/usr/bin/python3 $(REPO)/scripts/eval_table.py

# Door states fused over simulated drives (issue 20), door_state_drive_eval
# per sensor on DRIVE_SEEDS, plain and with a door toggled: JSON and per-drive
# lines (with the seed) in $(BUILD)/eval-drive/.
DRIVE_SENSORS ?= lidar64 lidar16 rgbd lidar32 lidar128
DRIVE_SEEDS ?= 3000-3019
.PHONY: eval-drive
eval-drive: build
	@mkdir -p $(BUILD)/eval-drive
	@for s in $(DRIVE_SENSORS); do \
	  $(BIN)/door_state_drive_eval --sensor $$s --seeds $(DRIVE_SEEDS) --verbose >$(BUILD)/eval-drive/$$s.json 2>$(BUILD)/eval-drive/$$s.log || exit 1; \
	  $(BIN)/door_state_drive_eval --sensor $$s --seeds $(DRIVE_SEEDS) --toggle auto --verbose >$(BUILD)/eval-drive/$$s-toggle.json 2>$(BUILD)/eval-drive/$$s-toggle.log || exit 1; \
	  echo "$$s: figures in $(BUILD)/eval-drive/$$s.json and $$s-toggle.json"; done

.PHONY: latency soak soak-drive
# The nodelet's latency from cloud in (stamped at publish) to DoorStateArray
# out, simulated clouds at 30 Hz (overload) and at a slow rate;
# LATENCY_SECONDS per case (default 30). Figures in $(BUILD)/latency/.
latency: build
	@$(REPO)/scripts/nodelet_latency.sh

# Simulated bags in a loop through the nodelet at 10 Hz for SOAK_SECONDS
# (default 600): clouds processed and dropped, latency, resident memory.
soak: build
	@$(REPO)/scripts/soak.sh

# A simulated drive bag played in a loop (use_sim_time, the clock going back
# at each loop) through the nodelet with tracked_doors, for SOAK_SECONDS
# (default 1800): resident memory, tracks, the last tracked_doors of each loop.
soak-drive: build
	@$(REPO)/scripts/soak_drive.sh

rviz-shot: build
	@$(REPO)/scripts/rviz_shot.sh

# Camera frames of each depth family with the doors found drawn on them:
# doc/gallery.png and its captions doc/gallery.txt.
gallery: build
	@/usr/bin/python3 $(REPO)/scripts/gallery.py

clean:
	rm -rf $(BUILD)
