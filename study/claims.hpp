// The paper's conclusions as claims: each a sentence built from the paper's numbers and ours,
// ending with whether the conclusion holds on these recordings. No verdict is written by hand.
#pragma once

#include <string>
#include <vector>

namespace canalsim::study {


struct Claim {
  std::string table;  // "table4"
  std::string text;   // the whole sentence, ending with its verdict
  bool holds = false;
  std::string why;    // for a claim that does not hold: its cause and figure (explanations.hpp)
};

// "SUBJECT at op1 and op2: paper +3.13 and +5.91 UNIT, here +2.10 and −0.40 UNIT — holds." The
// claim is that every difference is positive; it holds when every `here` difference is positive
// at the printed precision (≥ 0.005; the verdict names the places where it fails). Sizes of `where`, `paper` and `here` must match.
Claim difference_claim(const std::string& table, const std::string& subject,
                       const std::vector<std::string>& where, const std::vector<double>& paper,
                       const std::vector<double>& here, const std::string& unit = "points");

// "SUBJECT (RANGE_TEXT) at op3 and op4: paper 6.15 and 6.85, here 1.2 and 0.8 — does not hold
// (op3, op4)." Holds when every `here` value lies in [lower, upper].
Claim range_claim(const std::string& table, const std::string& subject, const std::string& range_text,
                  const std::vector<std::string>& where, const std::vector<double>& paper,
                  const std::vector<double>& here, double lower, double upper);

// "SUBJECT: paper BEST_PAPER, here BEST_HERE — holds." for "which model is best" claims; holds
// when the names are equal.
Claim same_claim(const std::string& table, const std::string& subject, const std::string& paper,
                 const std::string& here);

}  // namespace canalsim::study
