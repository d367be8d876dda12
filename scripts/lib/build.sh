# Sourced by scripts/demo and scripts/test: the one release build both use (the library, the
# glray command, the examples and the test binaries, with one set of features), so that running
# one after the other builds nothing again.
[ -x "$HOME/.cargo/bin/cargo" ] && export PATH="$HOME/.cargo/bin:$PATH"
cargo build --release --workspace --all-targets --locked
# The IceT-style MPI example host (examples/mpi), a C program: built with Open MPI's mpicc.
mkdir -p target/release/examples
if [ ! -x target/release/examples/icet_like ] || [ examples/mpi/icet_like.c -nt target/release/examples/icet_like ]; then
  mpicc -O2 examples/mpi/icet_like.c -o target/release/examples/icet_like -lOSMesa -lz -lm
fi
# The second, independent sort-last host (examples/mpi/direct_send.c: GLX windows, direct-send
# compositing), for the tests and scripts/bench-mpi.
if [ ! -x target/release/examples/direct_send ] || [ examples/mpi/direct_send.c -nt target/release/examples/direct_send ]; then
  mpicc -O2 examples/mpi/direct_send.c -o target/release/examples/direct_send -lGL -lX11 -lm
fi
