// Owning handles for SuiteSparse KLU's complex sparse LU (RAII: each KLU object freed once),
// and the solver of the frequency sweep: one symbolic analysis of the pattern, then per frequency
// a numeric factorisation of iωI − A and one solve.
//
// The unknowns are ordered along the canal (cell by cell), so iωI − A is a narrow band: the
// natural ordering (klu_analyze_given with no permutation) keeps the factors inside it and skips
// AMD's analysis; KLU's partial pivoting keeps the factorisation stable whatever ω.
#pragma once

#include <complex>
#include <memory>
#include <vector>

#include <klu.h>

namespace canalsim::linearize {

class KluComplexSolver {
 public:
  // A complex matrix in compressed columns (0-based, sorted rows): values[k] is column_start's
  // entry k. The pattern is analysed once here.
  KluComplexSolver(int size, std::vector<int> column_start, std::vector<int> row);
  KluComplexSolver(const KluComplexSolver&) = delete;
  KluComplexSolver& operator=(const KluComplexSolver&) = delete;

  // Factorises the matrix with these values (in the pattern's order), choosing pivots afresh;
  // false if it is singular.
  bool factorize(const std::vector<std::complex<double>>& values);
  // Factorises new values with the pivot sequence of the last factorize() (klu_z_refactor: no
  // allocation, no search); false if there is none or a pivot is zero. The caller checks the
  // solution's residual: the old pivots may not suit the new values.
  bool refactorize(const std::vector<std::complex<double>>& values);
  // Overwrites rhs by the solution of the last factorised matrix.
  void solve(std::vector<std::complex<double>>& rhs);

 private:
  struct SymbolicDeleter {
    klu_common* common;
    void operator()(klu_symbolic* s) const { klu_free_symbolic(&s, common); }
  };
  struct NumericDeleter {
    klu_common* common;
    void operator()(klu_numeric* n) const { klu_z_free_numeric(&n, common); }
  };
  int size_;
  std::vector<int> column_start_, row_;
  std::unique_ptr<klu_common> common_;  // owned first: the deleters below use it
  std::unique_ptr<klu_symbolic, SymbolicDeleter> symbolic_;
  std::unique_ptr<klu_numeric, NumericDeleter> numeric_;
};

}  // namespace canalsim::linearize
