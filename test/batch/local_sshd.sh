#!/usr/bin/env bash
# Debian's OpenSSH server on 127.0.0.1 for the batch tests (test/batch/test_batch_engines.cpp; doc/batch.md).
#   local_sshd.sh start DIR [HIDDEN]  generates a host key, a user key and DIR/sshd_config (a free port of its own),
#                                     starts /usr/sbin/sshd and waits until a login succeeds
#   local_sshd.sh stop DIR            stops that sshd
# Clients use `ssh -F DIR/ssh_config HOST` (for GNU parallel: PARALLEL_SSH="ssh -F DIR/ssh_config"), where HOST is
# hostA or hostB (two names for this machine, so a login list spreads samples over two "hosts"), or island: a host
# that does not share HIDDEN, because its logins see an empty private tmpfs there (a mount namespace of their own;
# needs root and HIDDEN given at start). All state (keys, config, known_hosts, pid file, log) is in DIR.
# Exit 1 with the log's tail when sshd does not start or no login succeeds.
set -uo pipefail

die() {
  echo "local_sshd: $1" >&2
  [ -n "${2:-}" ] && [ -f "$2" ] && { echo "--- last lines of $2:" >&2; tail -n 25 "$2" >&2; }
  exit 1
}

alive() {
  local pid=$1
  [ -n "$pid" ] && [ -r "/proc/$pid/stat" ] && [ "$(cut -d' ' -f3 "/proc/$pid/stat" 2>/dev/null)" != Z ]
}

free_port() {
  /usr/bin/python3 -c '
import socket
s = socket.socket()
s.bind(("127.0.0.1", 0))
print(s.getsockname()[1])'
}

make_keys() {
  ssh-keygen -q -t ed25519 -N '' -C implicit_sim_test_host -f "$DIR/host_key" || die "ssh-keygen (host key) failed"
  ssh-keygen -q -t ed25519 -N '' -C implicit_sim_test_user -f "$DIR/user_key" || die "ssh-keygen (user key) failed"
  cp "$DIR/user_key.pub" "$DIR/authorized_keys"
  if [ -n "$HIDDEN" ]; then
    ssh-keygen -q -t ed25519 -N '' -C implicit_sim_test_island -f "$DIR/island_key" || die "ssh-keygen failed"
    # The island's forced command: the client's command in a mount namespace with a fresh tmpfs over HIDDEN.
    cat >"$DIR/island_login" <<EOF
#!/bin/bash
exec /usr/bin/unshare --mount --propagation private /bin/bash -c \\
  'mount -t tmpfs island "\$0" && exec "\$SHELL" -c "\$SSH_ORIGINAL_COMMAND"' $(printf %q "$HIDDEN")
EOF
    chmod 755 "$DIR/island_login"
    echo "command=\"$DIR/island_login\",no-pty $(cat "$DIR/island_key.pub")" >>"$DIR/authorized_keys"
  fi
}

write_configs() {
  local port=$1 user
  user=$(id -un)
  cat >"$DIR/sshd_config" <<EOF
# Written by local_sshd.sh: logins by the keys in $DIR/authorized_keys only.
ListenAddress 127.0.0.1
Port $port
HostKey $DIR/host_key
AuthorizedKeysFile $DIR/authorized_keys
PubkeyAuthentication yes
PasswordAuthentication no
KbdInteractiveAuthentication no
PermitRootLogin prohibit-password
AllowUsers $user
UsePAM no
StrictModes no
PidFile $DIR/sshd.pid
LogLevel VERBOSE
MaxStartups 100:30:200
MaxSessions 100
EOF
  echo "[127.0.0.1]:$port $(cut -d' ' -f1,2 "$DIR/host_key.pub")" >"$DIR/known_hosts"
  cat >"$DIR/ssh_config" <<EOF
# Written by local_sshd.sh: hostA and hostB are this machine's sshd on port $port; island is a host without HIDDEN.
Host hostA hostB
  IdentityFile $DIR/user_key
Host island
  IdentityFile $DIR/island_key
Host *
  HostName 127.0.0.1
  Port $port
  User $user
  IdentitiesOnly yes
  UserKnownHostsFile $DIR/known_hosts
  StrictHostKeyChecking yes
  BatchMode yes
  LogLevel ERROR
EOF
}

start() {
  [ -x /usr/sbin/sshd ] || die "/usr/sbin/sshd is missing (Debian package openssh-server)"
  mkdir -p "$DIR" || die "cannot create $DIR"
  rm -f "$DIR"/host_key* "$DIR"/user_key* "$DIR"/island_key*
  # sshd's privilege separation directory (openssh-server's tmpfiles.d creates it at boot under systemd).
  [ "$(id -u)" != 0 ] || { mkdir -p /run/sshd && chmod 755 /run/sshd; }
  make_keys
  write_configs "$(free_port)"
  /usr/sbin/sshd -f "$DIR/sshd_config" -E "$DIR/sshd.log" 2>>"$DIR/sshd.log" || die "sshd did not start" "$DIR/sshd.log"
  for _ in $(seq 100); do
    ssh -F "$DIR/ssh_config" hostA true 2>"$DIR/ssh_client.log" && {
      echo "local_sshd: sshd $(cat "$DIR/sshd.pid") on 127.0.0.1; ssh -F $DIR/ssh_config hostA"
      return 0
    }
    sleep 0.1
  done
  cat "$DIR/ssh_client.log" >&2
  die "no login to sshd on 127.0.0.1 within 10 s (ssh -F $DIR/ssh_config hostA true)" "$DIR/sshd.log"
}

stop() {
  local pid
  pid=$(cat "$DIR/sshd.pid" 2>/dev/null) || return 0
  alive "$pid" || return 0
  kill -TERM "$pid"  # the listener; sessions end with their commands
  for _ in $(seq 100); do alive "$pid" || return 0; sleep 0.1; done
  kill -KILL "$pid"
  sleep 0.5
  alive "$pid" && die "sshd $pid still running after SIGKILL"
  return 0
}

[ $# -ge 2 ] && [ $# -le 3 ] || { echo "usage: local_sshd.sh {start DIR [HIDDEN]|stop DIR}" >&2; exit 2; }
DIR=$(realpath -m "$2")
HIDDEN=${3:+$(realpath -m "$3")}
case "$1" in
  start) start ;;
  stop) stop ;;
  *) echo "usage: local_sshd.sh {start DIR [HIDDEN]|stop DIR}" >&2; exit 2 ;;
esac
