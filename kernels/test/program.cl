// The test program (src/cl/program.rs, build_test_program): the production program, then the
// kernels only the tests use.

#include "program.cl"
#include "test/tests.cl"
#include "test/bsdf_test.cl"
