# The sources the parsers of outside files need (paths from the repository root), and the
# packages they link. Both builds use this one list: the fuzz project (tests/fuzz/CMakeLists.txt,
# clang with sanitizers) compiles exactly these, and the main build's fuzz_corpus_test links
# these alone, no photomat library, so a parser that gains a dependency fails the main build's
# link as it would fail the fuzz project's.
set(PHOTOMAT_FUZZ_PARSER_SOURCES
    core/atomic_file.cc
    core/colour.cc
    core/error.cc
    core/image.cc
    core/image_io.cc
    core/jpeg_structure.cc
    core/sample_encoding.cc
    core/json_file.cc
    core/light_direction.cc
    core/photometric_set.cc
    core/progress.cc
    capture/io/capture_manifest.cc
    capture/io/lp_file.cc
    core/text_parsing.cc
    represent/model/hsh.cc
    represent/model/light_basis.cc
    represent/model/light_interpolation.cc
    represent/stack/map_stack.cc
    represent/model/light_profile_basis.cc
    represent/model/representation.cc
    represent/model/shading.cc
    represent/model/neural_decoder.cc
    relight/formats/header_reader.cc
    relight/formats/positioned_file.cc
    relight/formats/ptm_file.cc
    relight/formats/ptm_jpeg.cc
    relight/formats/rti_file.cc)
set(PHOTOMAT_FUZZ_PARSER_LIBRARIES
    Eigen3::Eigen OpenImageIO::OpenImageIO nlohmann_json::nlohmann_json fmt::fmt spdlog::spdlog
    TBB::tbb opencv_core opencv_imgproc PkgConfig::LCMS2 PNG::PNG)
