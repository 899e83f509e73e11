# Radiosity Baker — developer entry points. `make demo` and `make test` set up
# .venv (idempotent: reinstalls only when requirements.txt changes) first.
PYTHON_BOOTSTRAP ?= $(shell command -v python3.11 || command -v python3)
VENV := .venv
PY := $(VENV)/bin/python
STAMP := $(VENV)/.requirements-installed
OUT ?= out
RIG := tools/blender_rig.sh
RIG_5_2 ?= /var/cache/blender-rig
RIG_4_3 ?= /var/cache/blender-rig-trixie

.PHONY: setup check-system demo test test-zink test-timing test-blender rigs bench bench-quick bench-production bench-lightmaps extension samples clean

setup: check-system $(STAMP)

check-system:
	@$(PYTHON_BOOTSTRAP) -c "import sys; sys.exit(0 if sys.version_info[:2] == (3, 11) else 1)" || \
	  { echo "error: Python 3.11 is needed (bpy 5.0.1 supports only 3.11); install python3.11 or set PYTHON_BOOTSTRAP"; exit 1; }
	@$(PYTHON_BOOTSTRAP) -c "import ctypes.util as u, sys; sys.exit(0 if u.find_library('EGL') and u.find_library('GL') else 1)" || \
	  { echo "error: OpenGL/EGL libraries missing; install them: sudo apt-get install libegl1 libegl-mesa0 libgl1-mesa-dri"; exit 1; }

$(STAMP): requirements.txt
	$(PYTHON_BOOTSTRAP) -m venv $(VENV)
	$(PY) -m pip install --quiet --disable-pip-version-check -r requirements.txt
	touch $@

# the main job: bake the Cornell sample through the add-on (bpy module) — EXR lightmaps,
# the baked .blend, a preview render and the solve report in out/
demo: setup sample_blends/.made
	$(PY) -m radiosity_addon bake sample_blends/cornell_box.blend --output-dir $(OUT)/cornell-lightmaps \
	  --save-as $(OUT)/cornell_box_baked.blend --preview $(OUT)/cornell-box-preview.png \
	  --report $(OUT)/cornell-box-report.json

test: setup
	$(VENV)/bin/ruff check .
	$(PY) -m pytest

# the tests marked gl (every shader and pass) again on a second OpenGL implementation, Mesa's zink
# over the Vulkan software device (needs: apt-get install mesa-vulkan-drivers)
ZINK := LIBGL_ALWAYS_SOFTWARE=1 MESA_LOADER_DRIVER_OVERRIDE=zink EGL_PLATFORM=surfaceless \
  XDG_RUNTIME_DIR=$${XDG_RUNTIME_DIR:-/tmp} RADIOSITY_EXPECT_RENDERER=zink
# Mesa 22.3's zink has crashed once in seven runs here inside a buffer's creation (a signal, not a
# failed test): a crash, and only a crash, is said and run once more
test-zink: setup
	$(ZINK) $(PY) -m pytest -m gl || { status=$$?; [ $$status -ge 128 ] || exit $$status; \
	  echo "zink crashed (exit $$status): running the gl tests once more"; $(ZINK) $(PY) -m pytest -m gl; }

# the wall-clock ratios `make test` leaves out (tests marked timing): run them on a quiet machine
test-timing: setup
	$(PY) -m pytest -m timing

# the real-Blender tier: the zip installed into Debian's Blender 5.2.2 and 4.3.2 (roots made by
# tools/blender_rig.sh: needs root, debootstrap and a Debian mirror; ~1-3 min each the first time),
# headless bakes, and the UI under Xvfb; screenshots and measurements in $(OUT)/real-blender/
test-blender: extension rigs
	BLENDER_RIG_DIR_5_2=$(RIG_5_2) BLENDER_RIG_DIR_4_3=$(RIG_4_3) $(PY) -m pytest tests/real_blender

rigs:
	BLENDER_RIG_SUITE=sid $(RIG) setup $(RIG_5_2)
	BLENDER_RIG_SUITE=trixie $(RIG) setup $(RIG_4_3)

# dist/radiosity_baker-<version>-<platform>.zip for linux-x64, windows-x64, macos-arm64
# (downloads the moderngl/glcontext wheels into wheels/, builds and validates with Blender's tool)
extension: setup
	$(PY) tools/build_extension.py --output-dir dist

# sample_blends/*.blend (the bundled Cornell box, a hand-made room and the five samples of
# tests/blender/test_blender_samples.py, tools/make_sample_blends.py says what each holds), in the format of the bpy
# module's Blender (5.0; not committed: Blender 4.x cannot open 5.x files, so each Blender makes its
# own: blender -b --factory-startup --python tools/make_sample_blends.py). The tests make them too.
samples: setup
	$(PY) tools/make_sample_blends.py
	touch sample_blends/.made

sample_blends/.made: tools/make_sample_blends.py bench/blend_scenes.py \
		bench/shapes.py | setup
	$(PY) tools/make_sample_blends.py
	touch $@

# accuracy vs time against Cycles and exact answers, and the dissertation's Table 5.1
# (the Cycles reference is cached in $(OUT)/bench*/cache, so reruns are cheap)
bench: setup
	$(PY) -m bench --output-dir $(OUT)/bench

bench-quick: setup
	$(PY) -m bench --quick --output-dir $(OUT)/bench-quick

# the production terrace (dense meshes, 20 materials in one object, a triangle soup, alpha-cut
# leaves, sun and sky; bench/production.py) on a quiet machine, ~1 h: how each stage
# grows from 50k to 500k triangles (10 objects; then 300k as one object and as 30) and the presets
# against Cycles at 50k, with pictures; the tables, plots and pictures go to docs/bench/production/
PRODUCTION_DOCS := docs/bench/production
bench-production: setup
	mkdir -p $(PRODUCTION_DOCS)
	$(PY) tools/measure_scaling.py --family production --triangles 50000 100000 200000 300000 500000 \
	  --quality draft --cycles 16 --output-dir $(OUT)/scaling-production
	$(PY) tools/measure_scaling.py --family production --objects 1 --triangles 300000 --quality draft \
	  --cycles 16 --output-dir $(OUT)/scaling-production-one
	$(PY) tools/measure_scaling.py --family production --objects 30 --triangles 300000 --quality draft \
	  --cycles 16 --output-dir $(OUT)/scaling-production-30
	$(PY) -m bench.production --triangles 50000 --output $(OUT)/production/p50k.blend
	$(PY) tools/measure_presets.py $(OUT)/production/p50k.blend --output-dir $(OUT)/presets-production \
	  --runs '{"quality": "draft"}' '{"quality": "good"}' '{"quality": "final"}' --reference 256 --cycles 16 64 \
	  --pictures $(OUT)/presets-production/pictures
	$(PY) tools/measure_presets.py $(OUT)/scaling-production/production_300000_10.blend \
	  --output-dir $(OUT)/presets-production-300k --runs '{"quality": "good"}' --reference 256 --cycles 16 64
	cp $(OUT)/presets-production-300k/presets.md $(PRODUCTION_DOCS)/presets_300k.md
	cp $(OUT)/scaling-production/scaling.md $(PRODUCTION_DOCS)/scaling.md
	cp $(OUT)/scaling-production/scaling.png $(PRODUCTION_DOCS)/scaling.png
	{ cat $(OUT)/scaling-production-one/scaling.md; tail -n +3 $(OUT)/scaling-production-30/scaling.md; } > $(PRODUCTION_DOCS)/objects.md
	cp $(OUT)/presets-production/presets.md $(OUT)/presets-production/presets.png $(PRODUCTION_DOCS)/
	mkdir -p $(PRODUCTION_DOCS)/pictures
	cp $(OUT)/presets-production/pictures/good_*.png $(PRODUCTION_DOCS)/pictures/

# lightmaps to look at beside Cycles': the Cornell box with its light 1 mm under the ceiling at
# final (automatic texel density: a wall 144 texels across) and the furnished 4k room at good, each
# object's texel RMS and pictures (ours | Cycles | difference) into docs/bench/lightmaps/, ~25 min
LIGHTMAP_DOCS := docs/bench/lightmaps
bench-lightmaps: setup sample_blends/.made
	$(PY) -m bench.cornell_gap --gap 0.001 --output $(OUT)/cornell/cornell_1mm.blend
	$(PY) tools/measure_presets.py $(OUT)/cornell/cornell_1mm.blend --output-dir $(OUT)/lightmaps/cornell-1mm \
	  --runs '{"quality": "final"}' --reference 512 --cycles 64 --pictures $(OUT)/lightmaps/cornell-1mm/pictures
	$(PY) -m bench.rooms --triangles 4000 --output $(OUT)/rooms/room_4k.blend
	$(PY) tools/measure_presets.py $(OUT)/rooms/room_4k.blend --output-dir $(OUT)/lightmaps/room \
	  --runs '{"quality": "good"}' --reference 128 --cycles 16 --pictures $(OUT)/lightmaps/room/pictures
	mkdir -p $(LIGHTMAP_DOCS)
	cp $(OUT)/lightmaps/cornell-1mm/presets.md $(LIGHTMAP_DOCS)/cornell_1mm.md
	cp $(OUT)/lightmaps/room/presets.md $(LIGHTMAP_DOCS)/room.md
	cp $(OUT)/lightmaps/cornell-1mm/pictures/final_ceiling.png $(OUT)/lightmaps/cornell-1mm/pictures/final_floor.png \
	  $(LIGHTMAP_DOCS)/
	cp $(OUT)/lightmaps/room/pictures/good_Floor.png $(OUT)/lightmaps/room/pictures/good_Wall_East.png \
	  $(OUT)/lightmaps/room/pictures/good_Shelf.png $(LIGHTMAP_DOCS)/

clean:
	rm -rf $(OUT) dist build .pytest_cache

# the README's tables of measured figures, rewritten from the JSON in docs/bench/ that the bench
# commands named next to each table write (standard library only; idempotent).
# Check without writing: python3 tools/readme_figures.py --check (exit 1: out of date)
.PHONY: readme-figures
readme-figures:
	$(PYTHON_BOOTSTRAP) tools/readme_figures.py

# docs/architecture.md's generated tables (the quality presets and the settings' defaults from
# radiosity_addon/core/settings.py, the core's layering from tests/test_layering.py), rewritten
# from the code (idempotent). Check without writing, links included:
# .venv/bin/python tools/architecture_tables.py --check (exit 1: out of date or a broken link)
.PHONY: architecture-tables
architecture-tables: setup
	$(PY) tools/architecture_tables.py
