#!/usr/bin/env bash
# tools/blender_rig.sh — run a real Blender binary (Debian's package, not the bpy module) on a
# Linux host without a GPU, headless or under Xvfb, inside a debootstrapped Debian root, with
# Mesa's llvmpipe for OpenGL. The real-Blender tests (`make test-blender`, tests/real_blender/)
# run Blender 5.2 (Debian sid) and 4.3 (Debian trixie) through it. Needs root and debootstrap.
#
#   tools/blender_rig.sh setup [DIR]            make the root (idempotent), print Blender's version
#   tools/blender_rig.sh run [--gui] [--screen WxHxD] -- ARGS...
#                                               run `blender ARGS...` in the root; the current
#                                               directory, /tmp, /proc, /dev, /sys are bind-mounted
#   tools/blender_rig.sh exec [--gui] -- CMD ARGS...   any command in the root the same way
#   tools/blender_rig.sh shot [--display :N] [--scale PCT] FILE.png
#                                               screenshot the Xvfb screen of a running --gui session
#   tools/blender_rig.sh version | status | help
#
# Environment:
#   BLENDER_RIG_DIR      the root (default /var/cache/blender-rig); `setup DIR` or `--dir DIR` too
#   BLENDER_RIG_SUITE    Debian suite for setup (default sid: Blender 5.2; trixie: Blender 4.3)
#   BLENDER_RIG_MIRROR   Debian mirror (default: the first .../debian URI in the host's apt sources)
#   BLENDER_RIG_SCREEN   Xvfb screen for --gui (default 1280x800x24)
#   BLENDER_RIG_HOME     HOME inside the root (default /root of the root, i.e. its own user config)
#   BLENDER_RIG_PASSENV  space-separated names of extra variables to pass into the root
#   BLENDER_*, MESA_*, LP_*, GALLIUM_*, LIBGL_*, PYTHONUNBUFFERED are passed through.
#   Inside: LIBGL_ALWAYS_SOFTWARE=1 GALLIUM_DRIVER=llvmpipe (Mesa's CPU renderer even where a GPU
#   exists). moderngl's standalone EGL context then prints "MESA-EGL: warning: Not allowed to
#   force software rendering when API explicitly selects a hardware device." -- harmless.
#
# Debian's Blender uses Debian's Python (sid's 5.2.2: 3.14; trixie's 4.3.2: 3.13), which may differ
# from blender.org's build of the same version: the extension's wheels must match it.
#
# Blender's own screenshot operators give all-black images under Xvfb + llvmpipe; take the X
# screen with `xwd -root -silent | convert xwd:- out.png` (both in the root) or `shot`.
#
# Mounts are made in a private mount namespace (unshare -m), so they vanish when the command
# ends, whatever way it ends; without unshare they are undone by a trap.
# (Adapted from the blender-rig tool of an earlier investigation; the project owns this copy.)
set -euo pipefail

PROG=blender_rig.sh
die() { echo "$PROG: error: $*" >&2; exit 1; }
note() { echo "$PROG: $*" >&2; }

RIG_DIR=${BLENDER_RIG_DIR:-/var/cache/blender-rig}
SUITE=${BLENDER_RIG_SUITE:-sid}
SCREEN=${BLENDER_RIG_SCREEN:-1280x800x24}
STATE_REL=.blender-rig            # state folder inside the root
# Debian's blender does not depend on what blender.org's builds bundle in their Python: numpy
# (add-ons rely on it), and cattrs + requests (the Extensions add-on bl_pkg fails to register
# without them: "No module named 'cattrs'"); so they are added here.
PACKAGES=(blender python3-numpy python3-cattr python3-requests
          xvfb x11-apps imagemagick libgl1-mesa-dri libegl-mesa0 libegl1 libglx-mesa0 libgl1 mesa-utils)

usage() { sed -n '2,/^set -euo/p' "$0" | sed '$d' | sed 's/^# \{0,1\}//'; }

need_root() { [ "$(id -u)" = 0 ] || die "must run as root (debootstrap, chroot and mount need it)"; }

mirror() {
  if [ -n "${BLENDER_RIG_MIRROR:-}" ]; then echo "$BLENDER_RIG_MIRROR"; return; fi
  local m
  m=$(cat /etc/apt/sources.list /etc/apt/sources.list.d/*.list /etc/apt/sources.list.d/*.sources 2>/dev/null |
      grep -v '^[[:space:]]*#' | grep -Eo 'https?://[^ ]+/debian/?( |$)' | grep -v security | head -n1 | tr -d ' ' || true)
  echo "${m:-http://deb.debian.org/debian}"
}

# -- mounts ----------------------------------------------------------------------------
# _mount_all ROOT BINDCWD: bind the host's /proc /dev /sys /tmp (and the cwd) into ROOT
MOUNTED=()
_mount_all() {
  local root=$1 bindcwd=$2
  mount -t proc proc "$root/proc"                       && MOUNTED+=("$root/proc")
  mount --rbind /sys "$root/sys"                        && MOUNTED+=("$root/sys")
  mount --make-rslave "$root/sys"
  mount --rbind /dev "$root/dev"                        && MOUNTED+=("$root/dev")
  mount --make-rslave "$root/dev"
  mount --bind /tmp "$root/tmp"                         && MOUNTED+=("$root/tmp")
  if [ "$bindcwd" = 1 ]; then
    local cwd; cwd=$(pwd -P)
    case "$cwd" in
      /|/proc|/proc/*|/sys|/sys/*|/dev|/dev/*|/tmp|/tmp/*) ;;   # already visible (or never bind these)
      "$root"|"$root"/*) ;;                                    # inside the root itself
      *) mkdir -p "$root$cwd"; mount --bind "$cwd" "$root$cwd" && MOUNTED+=("$root$cwd") ;;
    esac
  fi
}
_umount_all() {
  local i
  for (( i=${#MOUNTED[@]}-1; i>=0; i-- )); do
    umount -R "${MOUNTED[$i]}" 2>/dev/null || umount -R -l "${MOUNTED[$i]}" 2>/dev/null ||
      note "warning: could not unmount ${MOUNTED[$i]}"
  done
  MOUNTED=()
}

# The environment inside the root: a clean one, plus what the user asked for.
_chroot_env() {
  local -a e=(PATH=/usr/local/sbin:/usr/local/bin:/usr/sbin:/usr/bin:/sbin:/bin
              HOME="${BLENDER_RIG_HOME:-/root}" LANG=C.UTF-8 LC_ALL=C.UTF-8
              TERM="${TERM:-dumb}" LIBGL_ALWAYS_SOFTWARE=1 GALLIUM_DRIVER=llvmpipe)
  local v
  while IFS= read -r v; do
    case "$v" in
      BLENDER_RIG_*) ;;
      BLENDER_*|MESA_*|LP_*|GALLIUM_*|LIBGL_*|PYTHONUNBUFFERED|PYTHONFAULTHANDLER) e+=("$v=${!v}") ;;
    esac
  done < <(compgen -e)
  for v in ${BLENDER_RIG_PASSENV:-}; do [ -n "${!v+x}" ] && e+=("$v=${!v}"); done
  [ -n "${RIG_DISPLAY:-}" ] && e+=("DISPLAY=$RIG_DISPLAY")
  printf '%s\0' "${e[@]}"
}

# _inner ROOT BINDCWD GUI CMD...: runs in the (private) mount namespace
XVFB_PID=
_inner_cleanup() {
  local rc=$?
  if [ -n "$XVFB_PID" ] && kill -0 "$XVFB_PID" 2>/dev/null; then
    kill "$XVFB_PID" 2>/dev/null || true
    for _ in 1 2 3 4 5 6 7 8 9 10; do kill -0 "$XVFB_PID" 2>/dev/null || break; sleep 0.2; done
    kill -9 "$XVFB_PID" 2>/dev/null || true
  fi
  [ -n "${RIG_DISPLAY_FILE:-}" ] && rm -f "$RIG_DISPLAY_FILE"
  _umount_all
  exit "$rc"
}
_inner() {
  local root=$1 bindcwd=$2 gui=$3; shift 3
  trap _inner_cleanup EXIT
  trap 'exit 130' INT; trap 'exit 143' TERM; trap 'exit 129' HUP
  _mount_all "$root" "$bindcwd"
  local cwd; cwd=$(pwd -P)
  case "$cwd" in "$root"|"$root"/*) cwd=/ ;; esac
  if [ "$gui" = 1 ]; then
    local n xlog started=0
    for n in $(seq 99 160); do
      [ -e "/tmp/.X11-unix/X$n" ] || [ -e "/tmp/.X$n-lock" ] && continue
      xlog=/tmp/blender-rig-xvfb-$n.log
      chroot "$root" /usr/bin/Xvfb ":$n" -screen 0 "$SCREEN" -nolisten tcp -noreset +extension GLX \
        >"$xlog" 2>&1 &
      XVFB_PID=$!
      for _ in $(seq 1 100); do
        [ -S "/tmp/.X11-unix/X$n" ] && { started=1; break; }
        kill -0 "$XVFB_PID" 2>/dev/null || break       # lost a race for :$n, or a real failure
        sleep 0.1
      done
      [ "$started" = 1 ] && break
      kill "$XVFB_PID" 2>/dev/null || true; wait "$XVFB_PID" 2>/dev/null || true; XVFB_PID=
      grep -q 'already active' "$xlog" 2>/dev/null || die "Xvfb :$n did not start, see $xlog: $(tail -n1 "$xlog")"
    done
    [ "$started" = 1 ] || die "no free X display between :99 and :160"
    RIG_DISPLAY=":$n"
    mkdir -p "$root/$STATE_REL/displays"
    RIG_DISPLAY_FILE="$root/$STATE_REL/displays/$n"
    echo "$$" > "$RIG_DISPLAY_FILE"
    note "Xvfb on DISPLAY=:$n ($SCREEN), log $xlog"
  fi
  local -a env; mapfile -d '' env < <(_chroot_env)
  # not exec: the trap must run afterwards (stop Xvfb, unmount)
  set +e
  chroot "$root" /usr/bin/env -i "${env[@]}" /bin/sh -c 'cd "$1" 2>/dev/null || cd /; shift; exec "$@"' \
    sh "$cwd" "$@"
  local rc=$?
  set -e
  return "$rc"
}

# in_root BINDCWD GUI CMD...: run CMD in the root with the mounts, in a private namespace
in_root() {
  local bindcwd=$1 gui=$2; shift 2
  if unshare -m --propagation private true 2>/dev/null; then
    BLENDER_RIG_DIR=$RIG_DIR BLENDER_RIG_SCREEN=$SCREEN \
      unshare -m --propagation private -- "$SELF" __inner "$RIG_DIR" "$bindcwd" "$gui" "$@"
  else
    ( _inner "$RIG_DIR" "$bindcwd" "$gui" "$@" )
  fi
}

is_ready() {  # set up, with the package list of this version of the script
  [ -f "$RIG_DIR/$STATE_REL/ready" ] && [ -x "$RIG_DIR/usr/bin/blender" ] &&
    grep -qxF "packages=${PACKAGES[*]}" "$RIG_DIR/$STATE_REL/ready"
}
need_ready() {
  local hint=""; [ "$RIG_DIR" = /var/cache/blender-rig ] || hint=" $RIG_DIR"
  is_ready || die "no blender-rig root at $RIG_DIR (run: $PROG setup$hint)"
}

blender_version() { in_root 0 0 blender --version 2>/dev/null | head -n1; }

# -- setup -----------------------------------------------------------------------------
cmd_setup() {
  [ $# -le 1 ] || die "usage: $PROG setup [DIR]"
  [ $# = 1 ] && RIG_DIR=$1
  need_root
  case "$RIG_DIR" in /*) ;; *) RIG_DIR=$(pwd -P)/$RIG_DIR ;; esac
  RIG_DIR=${RIG_DIR%/}
  [ -n "$RIG_DIR" ] && [ "$RIG_DIR" != / ] || die "refusing to use / as the root"
  command -v debootstrap >/dev/null || die "debootstrap is not installed (apt-get install debootstrap)"
  mkdir -p "$(dirname "$RIG_DIR")"
  exec 9>"$RIG_DIR.lock"
  flock -n 9 || die "another '$PROG setup' holds $RIG_DIR.lock"

  if is_ready; then
    note "root already set up at $RIG_DIR ($(du -sh --one-file-system "$RIG_DIR" | cut -f1))"
    blender_version
    return 0
  fi
  local t0=$SECONDS mir; mir=$(mirror)

  if [ ! -f "$RIG_DIR/$STATE_REL/debootstrap-ok" ]; then
    if [ -d "$RIG_DIR" ] && [ -n "$(ls -A "$RIG_DIR")" ]; then
      [ -f "$RIG_DIR/$STATE_REL/owned" ] ||
        die "$RIG_DIR is not empty and not a blender-rig root; choose another DIR"
      awk -v d="$RIG_DIR" '$5 == d || index($5, d "/") == 1 {found = 1} END {exit !found}' /proc/self/mountinfo &&
        die "something is mounted under $RIG_DIR; unmount it first (grep $RIG_DIR /proc/self/mountinfo)"
      note "removing the unfinished root at $RIG_DIR"
      rm -rf --one-file-system "$RIG_DIR"
    fi
    mkdir -p "$RIG_DIR/$STATE_REL"
    touch "$RIG_DIR/$STATE_REL/owned"
    note "debootstrap --variant=minbase $SUITE $RIG_DIR $mir"
    # in a private mount namespace where possible, so the /proc etc. it mounts cannot leak
    local -a ns=(); unshare -m --propagation private true 2>/dev/null && ns=(unshare -m --propagation private --)
    "${ns[@]}" debootstrap --variant=minbase "$SUITE" "$RIG_DIR" "$mir" > "$RIG_DIR.debootstrap.log" 2>&1 ||
      die "debootstrap failed, see $RIG_DIR.debootstrap.log: $(grep -E '^[EW]:' "$RIG_DIR.debootstrap.log" | tail -n1)"
    touch "$RIG_DIR/$STATE_REL/debootstrap-ok"
    note "debootstrap done in $((SECONDS - t0)) s"
  fi

  # keep it small: no recommends, no docs/man/locales; no services started by postinsts
  mkdir -p "$RIG_DIR/etc/apt/apt.conf.d" "$RIG_DIR/etc/dpkg/dpkg.cfg.d"
  cat > "$RIG_DIR/etc/apt/apt.conf.d/90blender-rig" <<'EOF'
APT::Install-Recommends "false";
APT::Install-Suggests "false";
Acquire::Languages "none";
Dpkg::Use-Pty "false";
Acquire::Check-Valid-Until "false";
Acquire::Check-Date "false";
EOF
  cat > "$RIG_DIR/etc/dpkg/dpkg.cfg.d/90blender-rig-nodoc" <<'EOF'
path-exclude=/usr/share/doc/*
path-include=/usr/share/doc/*/copyright
path-exclude=/usr/share/man/*
path-exclude=/usr/share/info/*
path-exclude=/usr/share/locale/*
path-exclude=/usr/share/lintian/*
EOF
  printf '#!/bin/sh\nexit 101\n' > "$RIG_DIR/usr/sbin/policy-rc.d"; chmod 755 "$RIG_DIR/usr/sbin/policy-rc.d"
  # Blender lists mounted file systems through /etc/mtab (else: "Could not get a list of mounted file-systems")
  [ -e "$RIG_DIR/etc/mtab" ] || ln -sfn ../proc/self/mounts "$RIG_DIR/etc/mtab"
  echo "deb $mir $SUITE main" > "$RIG_DIR/etc/apt/sources.list"

  note "apt-get install ${PACKAGES[*]} (in the root)"
  local alog=$RIG_DIR.apt.log t1=$SECONDS
  if ! in_root 0 0 sh -c 'export DEBIAN_FRONTEND=noninteractive;
        apt-get -q update && apt-get -q -y install "$@" && apt-get clean' sh "${PACKAGES[@]}" > "$alog" 2>&1; then
    die "apt-get in the root failed, see $alog: $(grep -E '^(E:|W:|dpkg: error)' "$alog" | tail -n1)"
  fi
  rm -rf "$RIG_DIR"/var/lib/apt/lists/*_Packages* "$RIG_DIR"/var/cache/apt/*.bin
  note "packages installed in $((SECONDS - t1)) s (log $alog)"

  local v; v=$(blender_version) || true
  case "$v" in Blender*) ;; *) die "blender does not start in the root: $(in_root 0 0 blender --version 2>&1 | tail -n1)" ;; esac
  in_root 0 0 sh -c 'command -v Xvfb && command -v xwd && command -v convert' >/dev/null ||
    die "Xvfb, xwd or convert missing in the root"
  local py; py=$(in_root 0 0 blender -b --factory-startup --python-expr \
      'import sys; print("PYTHON", sys.version.split()[0])' 2>/dev/null | sed -n 's/^PYTHON //p')
  { echo "suite=$SUITE"; echo "mirror=$mir"; echo "blender=$v"; echo "python=$py"
    echo "packages=${PACKAGES[*]}"; date -u +date=%FT%TZ; } > "$RIG_DIR/$STATE_REL/ready"
  local tag; tag=cp$(echo "$py" | cut -d. -f1,2 | tr -d .)
  note "Blender's Python is $py: wheels bundled in an extension must include $tag ones"
  note "setup took $((SECONDS - t0)) s; root $RIG_DIR is $(du -sh --one-file-system "$RIG_DIR" | cut -f1)"
  [ "$RIG_DIR" = /var/cache/blender-rig ] || note "use it with: BLENDER_RIG_DIR=$RIG_DIR $PROG run ... (or $PROG --dir $RIG_DIR run ...)"
  echo "$v"
}

# -- run / exec ------------------------------------------------------------------------
cmd_run() {  # cmd_run blender|exec ARGS...
  local what=$1; shift
  local gui=0
  while [ $# -gt 0 ]; do
    case "$1" in
      --gui) gui=1; shift ;;
      --screen) [ $# -ge 2 ] || die "--screen needs WxHxD"; SCREEN=$2; shift 2 ;;
      --screen=*) SCREEN=${1#--screen=}; shift ;;
      --) shift; break ;;
      -*) [ "$what" = blender ] && break; die "unknown option $1 (put the command after --)" ;;
      *) break ;;
    esac
  done
  need_root; need_ready
  if [ "$what" = blender ]; then
    set -- blender "$@"
  else
    [ $# -ge 1 ] || die "usage: $PROG exec [--gui] -- CMD [ARGS...]"
  fi
  in_root 1 "$gui" "$@"
}

# -- shot ------------------------------------------------------------------------------
cmd_shot() {
  local disp='' scale='' out=
  while [ $# -gt 0 ]; do
    case "$1" in
      --display) disp=$2; shift 2 ;;
      --scale) scale=$2; shift 2 ;;
      -*) die "unknown option $1" ;;
      *) [ -z "$out" ] || die "usage: $PROG shot [--display :N] [--scale PCT] FILE.png"; out=$1; shift ;;
    esac
  done
  [ -n "$out" ] || die "usage: $PROG shot [--display :N] [--scale PCT] FILE.png"
  need_root; need_ready
  if [ -z "$disp" ]; then
    local f n live=()
    for f in "$RIG_DIR/$STATE_REL/displays"/*; do
      [ -f "$f" ] || continue
      n=${f##*/}
      if kill -0 "$(cat "$f")" 2>/dev/null && [ -S "/tmp/.X11-unix/X$n" ]; then live+=(":$n"); fi
    done
    [ ${#live[@]} -ge 1 ] || die "no running '$PROG run --gui' session (give --display :N)"
    [ ${#live[@]} -eq 1 ] || die "several sessions run (${live[*]}); give --display"
    disp=${live[0]}
  fi
  local -a conv=(convert xwd:- )
  [ -n "$scale" ] && conv+=(-resize "$scale%")
  conv+=(png:-)
  local tmp; tmp=$(mktemp "${out}.XXXXXX")
  if in_root 0 0 sh -c 'd=$1; shift; xwd -root -silent -display "$d" | "$@"' sh "$disp" "${conv[@]}" > "$tmp"; then
    mv -f "$tmp" "$out"; note "wrote $out ($disp)"
  else
    rm -f "$tmp"; die "screenshot of $disp failed"
  fi
}

cmd_status() {
  if is_ready; then
    cat "$RIG_DIR/$STATE_REL/ready"
    echo "size=$(du -sh --one-file-system "$RIG_DIR" | cut -f1)"
  else
    echo "no blender-rig root at $RIG_DIR"; return 1
  fi
}

main() {
  if [ "${1:-}" = __inner ]; then
    shift; RIG_DIR=$1; shift; _inner "$RIG_DIR" "$@"; return $?
  fi
  if [ "${1:-}" = --dir ]; then [ $# -ge 2 ] || die "--dir needs DIR"; RIG_DIR=$2; shift 2; fi
  case "${1:-help}" in
    setup)   shift; cmd_setup "$@" ;;
    run)     shift; cmd_run blender "$@" ;;
    exec)    shift; cmd_run exec "$@" ;;
    shot)    shift; cmd_shot "$@" ;;
    version) need_root; need_ready; blender_version ;;
    status)  cmd_status ;;
    help|-h|--help) usage ;;
    *) die "unknown command '$1' (try: $PROG help)" ;;
  esac
}

SELF=$(readlink -f "$0")
# one line, so that bash has read the whole file before running anything (safe to edit while in use)
main "$@"; exit $?
