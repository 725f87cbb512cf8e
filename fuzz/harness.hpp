// The properties the fuzz targets check, one function per input layer. Shared by the libFuzzer
// targets (fuzz/*_fuzz.cpp, clang) and the replay of fuzz/regressions/ in the main test suite
// (tests/fuzz/regressions_test.cpp, g++), so that an input that ever failed stays a test.
//
// Each function takes arbitrary bytes and returns normally when canalsim handled them as its
// contract says; a breach aborts (libFuzzer then saves the input): any exception other than
// InputError, a crash or a sanitizer report, or the property named in the function's comment.
#pragma once

#include <string_view>

namespace canalsim::fuzz {

// The TOML scenario loader: a scenario, or an InputError.
void scenario_input(std::string_view bytes);

// The recording reader: a recording, or an InputError; a recording read is written back by
// format_recording and reads again with the same metadata, columns and rows.
void recording_input(std::string_view bytes);

// The fitters on a recording: the first byte chooses the command — `fit -m MODEL` for each of the
// ten reduced models, `diagnose --model MODEL` (the second byte chooses it), or `resample
// --period P` — and the rest is the recording (arbitrary metadata and values), written to a
// temporary file and given to the command as the user would. Exit status 0 or 1; a status 1
// prints exactly one "canalsim: error: ..." line on stderr; a status 0 prints no non-finite
// number (nan, inf) on stdout.
void fitting_input(std::string_view bytes);

// The command line's argument layer: the bytes, split at NUL, are argv[1..] (at most 24); every
// subcommand's work is switched off, so only parsing, validators and error reporting run. Exit
// status 0 or 1; a status 1 prints exactly one line "canalsim: error: ..." on stderr.
void cli_arguments_input(std::string_view bytes);

}  // namespace canalsim::fuzz
