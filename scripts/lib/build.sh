# Sourced by scripts/demo and scripts/test: the one release build both use (the library, the
# glray command, the examples and the test binaries, with one set of features), so that running
# one after the other builds nothing again.
[ -x "$HOME/.cargo/bin/cargo" ] && export PATH="$HOME/.cargo/bin:$PATH"
cargo build --release --workspace --all-targets --locked
