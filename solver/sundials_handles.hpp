// Owning handles for the SUNDIALS objects the steady-state solver uses (RAII for every SUNDIALS
// and KLU object). Each handle frees its object once, in its destructor, whatever path
// leaves the scope; none is copyable, all are movable. The sundials::Context must outlive every
// object created with it: declare it first, so it is destroyed last.
//
//   sundials::Context context;
//   VectorHandle u(N_VNew_Serial(n, context));
//   MatrixHandle J(SUNSparseMatrix(n, n, nnz, CSC_MAT, context));
//   LinearSolverHandle ls(SUNLinSol_KLU(u.get(), J.get(), context));   // owns KLU's factors
//   KinsolHandle kin(KINCreate(context));
#pragma once

#include <memory>

#include <kinsol/kinsol.h>
#include <nvector/nvector_serial.h>
#include <sundials/sundials_context.h>
#include <sundials/sundials_linearsolver.h>
#include <sundials/sundials_matrix.h>

namespace canalsim::solver {

struct VectorDeleter {
  void operator()(N_Vector v) const { N_VDestroy(v); }
};
struct MatrixDeleter {
  void operator()(SUNMatrix m) const { SUNMatDestroy(m); }
};
// SUNLinSolFree of a KLU solver also frees KLU's symbolic and numeric factorisations.
struct LinearSolverDeleter {
  void operator()(SUNLinearSolver s) const { SUNLinSolFree(s); }
};
struct KinsolDeleter {
  void operator()(void* memory) const { KINFree(&memory); }
};

using VectorHandle = std::unique_ptr<std::remove_pointer_t<N_Vector>, VectorDeleter>;
using MatrixHandle = std::unique_ptr<std::remove_pointer_t<SUNMatrix>, MatrixDeleter>;
using LinearSolverHandle = std::unique_ptr<std::remove_pointer_t<SUNLinearSolver>, LinearSolverDeleter>;
using KinsolHandle = std::unique_ptr<void, KinsolDeleter>;

}  // namespace canalsim::solver
