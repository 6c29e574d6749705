# What the MPI shell tests share. Sourced after they set mpiexec: root may
# start ranks, a rank may have a core of its own or not, and each check
# counts as passed or failed.
export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1 OMPI_MCA_rmaps_base_oversubscribe=1
passed=0
failures=0
ok() { passed=$((passed + 1)); }
fail() { echo "FAIL: $*"; failures=$((failures + 1)); }
# mpi K COMMAND...: COMMAND on K ranks, ended after 300 s.
mpi() { local k=$1; shift; timeout 300 "$mpiexec" --oversubscribe -np "$k" "$@"; }
