// test_exec.cpp's cases on CudaExec: nvcc compiles a source as CUDA, which
// the backend's lambdas need, only under a .cu name.
#include "test_exec.cpp"
