/* The PETSc and MPI declarations bound by build.rs (allowlisted there). */
#include <petscksp.h>
