/* Everything the bindings cover: SNES pulls in KSP, PC, Mat, Vec, IS and the options database. */
#include <petscsnes.h>
#include <petsclog.h>
