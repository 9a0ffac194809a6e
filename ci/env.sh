# Sourced by the ci/ scripts: MPI settings every mpirun here needs (see docs/guide.md, "System set-up").
export OMPI_ALLOW_RUN_AS_ROOT=1
export OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1
# Without this, concurrent 2-rank jobs busy-wait and take 40x longer.
export OMPI_MCA_mpi_yield_when_idle=1
export CARGO_TERM_COLOR=never
# One thread per rank in BLAS, should a threaded OpenBLAS be the one installed (ci/setup).
export OPENBLAS_NUM_THREADS=1
