#include "linearize/klu_complex.hpp"

#include <stdexcept>

namespace canalsim::linearize {

KluComplexSolver::KluComplexSolver(int size, std::vector<int> column_start, std::vector<int> row)
    : size_(size), column_start_(std::move(column_start)), row_(std::move(row)),
      common_(std::make_unique<klu_common>()), symbolic_(nullptr, {common_.get()}), numeric_(nullptr, {common_.get()}) {
  klu_defaults(common_.get());
  common_->btf = 0;  // one band, no block triangular form to find
  symbolic_.reset(klu_analyze_given(size_, column_start_.data(), row_.data(), nullptr, nullptr, common_.get()));
  if (!symbolic_) throw std::runtime_error("KLU could not analyse the linearised system's pattern");
}

bool KluComplexSolver::factorize(const std::vector<std::complex<double>>& values) {
  // std::complex<double> is layout-compatible with double[2] (C++ [complex.numbers]), which is
  // KLU's interleaved complex storage.
  auto* data = const_cast<double*>(reinterpret_cast<const double*>(values.data()));
  numeric_.reset(klu_z_factor(column_start_.data(), row_.data(), data, symbolic_.get(), common_.get()));
  return numeric_ != nullptr && common_->status == KLU_OK;
}

bool KluComplexSolver::refactorize(const std::vector<std::complex<double>>& values) {
  if (!numeric_) return false;
  auto* data = const_cast<double*>(reinterpret_cast<const double*>(values.data()));
  return klu_z_refactor(column_start_.data(), row_.data(), data, symbolic_.get(), numeric_.get(), common_.get()) &&
         common_->status == KLU_OK;
}

void KluComplexSolver::solve(std::vector<std::complex<double>>& rhs) {
  klu_z_solve(symbolic_.get(), numeric_.get(), size_, 1, reinterpret_cast<double*>(rhs.data()), common_.get());
}

}  // namespace canalsim::linearize
