# Sourced by scripts: starts an X server of our own (it picks a free display and writes its
# number), exports DISPLAY, and stops it by PID when the script exits.
display_file=$(mktemp)
Xvfb -displayfd 9 -noreset -nolisten tcp -screen 0 1280x1024x24 9>"$display_file" 2>/dev/null &
xvfb_pid=$!
trap 'kill "$xvfb_pid" 2>/dev/null || true; rm -f "$display_file"' EXIT
for _ in $(seq 100); do [ -s "$display_file" ] && break; sleep 0.1; done
[ -s "$display_file" ] || { echo "Xvfb did not start" >&2; exit 1; }
export DISPLAY=":$(cat "$display_file")"
