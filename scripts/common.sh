# Shared by scripts/demo and scripts/test: install Debian packages, build the catkin workspace.
# Source it; it sets WS (the catkin workspace, default /tmp/implicit_sim_ws) and REPO.
REPO=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
WS=${IMPLICIT_SIM_WS:-/tmp/implicit_sim_ws}
# Debian's python3 first: a pyenv python on PATH breaks catkin and rostest (they need Debian's ROS modules).
export PATH=/usr/bin:/bin:/usr/sbin:/sbin:$PATH
export ROS_HOME=$WS/.ros ROS_LOG_DIR=$WS/.ros/log ROS_HOSTNAME=localhost

# munge, slurmctld, slurmd, slurm-client and openssh-server: test_batch_engines starts a one-node Slurm and an sshd of
# its own (test/batch/local_slurm.sh, local_sshd.sh); the packages' services are not started by the test.
# pybind11, numpy, setuptools and catkin-pkg: the Python API (doc/python.md); pytest: its tests (test/python); ffmpeg:
# the README's animations (scripts/make_animations) and their test.
APT_PACKAGES="build-essential cmake pkg-config googletest libgtest-dev catkin libroscpp-dev libtf2-ros-dev
  libgeometry-msgs-dev ros-geometry-msgs libsensor-msgs-dev ros-sensor-msgs libvisualization-msgs-dev libstd-msgs-dev ros-std-msgs libstd-srvs-dev
  libros-rosgraph-msgs-dev ros-message-generation ros-message-runtime librostest-dev python3-rostest
  libeigen3-dev coinor-libipopt-dev libsuitesparse-dev liburdfdom-dev libtinyxml2-dev libdiagnostic-updater-dev python3-rosbag python3-matplotlib locales
  parallel python3-yaml python3-rospy python3-geometry-msgs python3-sensor-msgs python3-tf2-msgs python3-visualization-msgs
  python3-diagnostic-msgs python3-rostopic
  libactionlib-dev libactionlib-msgs-dev ros-actionlib-msgs python3-actionlib python3-actionlib-msgs
  python3-std-srvs ros-std-srvs python3-rosservice python3-rosnode python3-roslaunch rosbash gdb valgrind
  libdynamic-reconfigure-config-init-mutex-dev python3-dynamic-reconfigure
  libinteractive-markers-dev python3-interactive-markers libroslib-dev
  libassimp-dev libqhull-dev ros-robot-state-publisher python3-tf2-ros
  libtrajectory-msgs-dev ros-trajectory-msgs python3-trajectory-msgs
  munge slurmctld slurmd slurm-client openssh-server
  pybind11-dev python3-pybind11 python3-numpy python3-pytest python3-setuptools python3-catkin-pkg ffmpeg"

install_packages() {
  local missing=""
  for p in $APT_PACKAGES; do
    dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing="$missing $p"
  done
  if [ -n "$missing" ] || [ -n "${IMPLICIT_SIM_FORCE_APT:-}" ]; then
    echo "[implicit_sim] installing Debian packages (missing:${missing:- none})"
    local sudo=""
    [ "$(id -u)" = 0 ] || sudo=sudo
    export DEBIAN_FRONTEND=noninteractive
    $sudo apt-get update
    $sudo apt-get -o DPkg::Lock::Timeout=900 install -y --no-install-recommends $APT_PACKAGES
  fi
  ensure_test_locale
}

# The locale tests (test/core/test_locale.cpp) need de_DE.UTF-8 (',' as decimal separator); they fail without it.
ensure_test_locale() {
  locale -a 2>/dev/null | grep -qi '^de_DE\.utf-\?8$' && return 0
  echo "[implicit_sim] generating the de_DE.UTF-8 locale"
  local sudo=""
  [ "$(id -u)" = 0 ] || sudo=sudo
  if grep -q '^# *de_DE\.UTF-8 UTF-8' /etc/locale.gen 2>/dev/null; then
    $sudo sed -i 's/^# *\(de_DE\.UTF-8 UTF-8\)/\1/' /etc/locale.gen
  elif ! grep -q '^de_DE\.UTF-8 UTF-8' /etc/locale.gen 2>/dev/null; then
    echo "de_DE.UTF-8 UTF-8" | $sudo tee -a /etc/locale.gen >/dev/null
  fi
  $sudo locale-gen
}

build_workspace() {
  mkdir -p "$WS/src"
  ln -sfn "$REPO" "$WS/src/implicit_sim"
  # -g1 (line tables, enough for backtraces): full -g makes the Eigen-heavy files compile 30-40 % slower, and debug
  # information never changes the code generated. A unity build (CMake compiles the sources of a target in batches)
  # parses Eigen and the ROS headers once a batch instead of once a file: half the compile time, the same numbers
  # (doc/testing.md, "How the run is scheduled").
  (cd "$WS" && catkin_make -DPYTHON_EXECUTABLE=/usr/bin/python3 -DCMAKE_BUILD_TYPE=RelWithDebInfo \
    "-DCMAKE_CXX_FLAGS_RELWITHDEBINFO=-O2 -g1 -DNDEBUG" -DCMAKE_UNITY_BUILD=ON -DCMAKE_UNITY_BUILD_BATCH_SIZE=16 -j2 >"$WS/build.log" 2>&1) || {
    tail -n 60 "$WS/build.log"; echo "[implicit_sim] build failed (full log: $WS/build.log)"; return 1; }
  echo "[implicit_sim] built in $WS"
}
