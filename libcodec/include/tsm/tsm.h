/* tsm: Topological Surgery mesh compression, C API for bindings.
 *
 *   tsm_mesh* m = NULL; char err[256];
 *   if (tsm_decode(bytes, size, NULL, &m, err, sizeof err) != TSM_OK) puts(err);
 *   ... tsm_mesh_positions(m), tsm_mesh_indices(m) ...
 *   tsm_mesh_free(m);
 *
 * Return codes are the values of tsm::ErrorCode (0 = ok). Error messages are
 * written NUL-terminated into err (truncated to err_size) when err is non-NULL.
 */
#ifndef TSM_H_
#define TSM_H_

#include <stddef.h>
#include <stdint.h>

#ifdef __cplusplus
extern "C" {
#endif

enum {
  TSM_OK = 0,
  TSM_INVALID_ARGUMENT = 1,
  TSM_IO_ERROR = 2,
  TSM_PARSE_ERROR = 3,
  TSM_CORRUPT_DATA = 4,
  TSM_UNSUPPORTED = 5,
  TSM_LIMIT_EXCEEDED = 6,
  TSM_INTERNAL = 7
};

typedef struct tsm_mesh tsm_mesh;

typedef struct tsm_decode_options {
  uint64_t max_vertices; /* 0 = no limit besides the format's own */
  uint64_t max_faces;
  uint64_t max_corners; /* 0 = 16 x max_faces when that is set */
  int threads;          /* segments decoded in parallel; 0 = one per core */
} tsm_decode_options;

typedef struct tsm_encode_options {
  int quantization_bits; /* 1..30, 0 = default (14) */
  int level;             /* 0..9, -1 = default */
  uint32_t segment_faces; /* faces per segment at most; 0 = default (2^18) */
  int threads;            /* segments coded in parallel; 0 = one per core */
} tsm_encode_options;

/* Decodes a .tsm buffer. options may be NULL. On success *out owns a mesh. */
int tsm_decode(const uint8_t* data, size_t size, const tsm_decode_options* options, tsm_mesh** out, char* err,
               size_t err_size);

/* Builds a mesh from positions (3 floats per vertex) and faces given as
 * face_sizes (face_count entries) and corner indices; face_sizes may be NULL
 * for triangles only. The arrays are copied. */
int tsm_mesh_create(const float* positions, size_t vertex_count, const uint32_t* face_sizes, size_t face_count,
                    const uint32_t* indices, size_t index_count, tsm_mesh** out, char* err, size_t err_size);

/* Encodes a mesh. On success *out is a malloc'ed buffer the caller frees with tsm_free. */
int tsm_encode(const tsm_mesh* mesh, const tsm_encode_options* options, uint8_t** out, size_t* out_size, char* err,
               size_t err_size);

/* Streaming decode: feed bytes as they arrive; each segment is decoded as
 * soon as its bytes are all in.
 *
 *   tsm_stream* s = tsm_stream_new(NULL);
 *   while (read a chunk) if (tsm_stream_feed(s, chunk, n, err, sizeof err)) break;
 *   ... after each feed, tsm_stream_mesh(s) holds the finished segments ...
 *   tsm_stream_finish(s, err, sizeof err);  tsm_stream_free(s);
 */
typedef struct tsm_stream tsm_stream;
/* options may be NULL (options->threads is not used). Returns NULL only when out of memory. */
tsm_stream* tsm_stream_new(const tsm_decode_options* options);
/* Feeds size bytes (any chunking); decodes every segment whose bytes are all in.
 * Returns TSM_OK or an error code (the stream is then failed and stays failed). */
int tsm_stream_feed(tsm_stream* s, const uint8_t* data, size_t size, char* err, size_t err_size);
/* Declares the end of the input: TSM_OK when the whole file was decoded, else an error (truncated file). */
int tsm_stream_finish(tsm_stream* s, char* err, size_t err_size);
/* Segments in the file (0 until the header is in) and segments decoded so far. */
size_t tsm_stream_segment_count(const tsm_stream* s);
size_t tsm_stream_segments_done(const tsm_stream* s);
/* The mesh decoded so far (vertices and faces of the finished segments; it only grows: the
 * vertices and faces of segment k come after those of segments < k, and faces of segment k only
 * reference vertices of segments <= k). Valid until the next feed/finish/free; read it with tsm_mesh_*. */
const tsm_mesh* tsm_stream_mesh(const tsm_stream* s);
void tsm_stream_free(tsm_stream* s);

size_t tsm_mesh_vertex_count(const tsm_mesh* mesh);
size_t tsm_mesh_face_count(const tsm_mesh* mesh);
size_t tsm_mesh_index_count(const tsm_mesh* mesh);
const float* tsm_mesh_positions(const tsm_mesh* mesh);      /* 3 * vertex_count */
const uint32_t* tsm_mesh_face_offsets(const tsm_mesh* mesh); /* face_count + 1 */
const uint32_t* tsm_mesh_indices(const tsm_mesh* mesh);      /* index_count */

void tsm_mesh_free(tsm_mesh* mesh);
void tsm_free(void* buffer);
const char* tsm_version(void);

#ifdef __cplusplus
}
#endif

#endif /* TSM_H_ */
