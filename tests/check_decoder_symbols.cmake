# ctest decoder.no_encoder_symbols: the decoder library (libtsm_decoder.a)
# neither defines nor calls the encoder's entry points (tsm::encode,
# tsm_encode) or zstd's compressor (ZSTD_compress*).
#   cmake -DNM=<nm> -DLIB=<libtsm_decoder.a> -P check_decoder_symbols.cmake
execute_process(COMMAND ${NM} -A ${LIB} OUTPUT_VARIABLE symbols RESULT_VARIABLE rc)
if(NOT rc EQUAL 0)
  message(FATAL_ERROR "${NM} ${LIB} failed (${rc})")
endif()
string(REGEX MATCHALL "[^\n]*( ZSTD_compress| tsm_encode| _ZN3tsm6encodeE)[^\n]*" found "${symbols}")
if(found)
  string(REPLACE ";" "\n" found "${found}")
  message(FATAL_ERROR "the decoder library names encoder symbols:\n${found}")
endif()
string(REGEX MATCHALL "[^\n]* T _ZN3tsm6decodeE[^\n]*" decode "${symbols}")
if(NOT decode)
  message(FATAL_ERROR "tsm::decode not found in ${LIB}: is it the decoder library?")
endif()
message(STATUS "libtsm_decoder.a: no encoder entry point, no zstd compressor")
