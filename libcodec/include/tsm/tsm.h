/* tsm: Topological Surgery mesh compression, C API for bindings.
 *
 *   tsm_mesh* m = NULL; char err[256];
 *   if (tsm_decode(bytes, size, NULL, &m, err, sizeof err) != TSM_OK) puts(err);
 *   ... tsm_mesh_positions(m), tsm_mesh_indices(m), tsm_mesh_attribute_values(m, 0) ...
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
  /* Attribute quantization bits, 1..24; 0 = default (normals 10, octahedral; texture
   * coordinates 12, float colours 10, other float attributes 16; integer types are exact). */
  int normal_bits;
  int texcoord_bits;
  int color_bits;
  int generic_bits;
  int keep_order;      /* nonzero: the decoded mesh keeps the input's vertex, face and corner order */
  int lossless;        /* nonzero: every float32 coordinate comes back bit for bit (quantization_bits unused) */
  int allow_nonfinite; /* with lossless, nonzero: NaN and infinite coordinates are kept (else refused) */
  int progressive;     /* nonzero: a base mesh then batches of vertex splits (positions and faces only) */
} tsm_encode_options;

/* Decodes a .tsm buffer. options may be NULL. On success *out owns a mesh. */
int tsm_decode(const uint8_t* data, size_t size, const tsm_decode_options* options, tsm_mesh** out, char* err,
               size_t err_size);

/* Builds a mesh from positions (3 floats per vertex) and faces given as
 * face_sizes (face_count entries) and corner indices; face_sizes may be NULL
 * for triangles only. The arrays are copied. */
int tsm_mesh_create(const float* positions, size_t vertex_count, const uint32_t* face_sizes, size_t face_count,
                    const uint32_t* indices, size_t index_count, tsm_mesh** out, char* err, size_t err_size);

/* Encodes a mesh (with its attributes and metadata). On success *out is a malloc'ed buffer the
 * caller frees with tsm_free. */
int tsm_encode(const tsm_mesh* mesh, const tsm_encode_options* options, uint8_t** out, size_t* out_size, char* err,
               size_t err_size);

/* tsm_encode, also giving where the decoded mesh's vertices and faces come
 * from in the input (tsm::EncodeMapping): *vertex_from (vertex_count
 * entries), *face_from and *first_corner (face_count entries each) are
 * malloc'ed arrays the caller frees with tsm_free. */
int tsm_encode_mapped(const tsm_mesh* mesh, const tsm_encode_options* options, uint8_t** out, size_t* out_size,
                      uint32_t** vertex_from, uint32_t** face_from, uint32_t** first_corner, char* err,
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
 * reference vertices of segments <= k). Valid until the next feed/finish/free; read it with tsm_mesh_*.
 * Its attributes appear with the first segment and grow the same way: vertex and face values
 * follow the vertices and faces, a corner attribute's values of segment k follow those of the
 * segments before it, and the corner indices of segment k (one per new corner) name values of
 * segments <= k. */
const tsm_mesh* tsm_stream_mesh(const tsm_stream* s);
void tsm_stream_free(tsm_stream* s);

/* Progressive files (a base mesh, then batches of vertex splits): the stream's
 * mesh is a level of detail of the whole shape, from the base (shown as soon as
 * it is whole) to the full mesh; batches change faces in place, so a client
 * redraws the whole mesh at each level rather than appending. To see every
 * level, even when one chunk holds several batches:
 *
 *   tsm_stream_stop_at_levels(s, 1);
 *   while (read a chunk) {
 *     int rc = tsm_stream_feed(s, chunk, n, err, sizeof err);
 *     while (rc == TSM_OK) {
 *       if (tsm_stream_progressive(s)) draw(tsm_stream_mesh(s), tsm_stream_batches_done(s),
 *                                           tsm_stream_level_error(s));
 *       if (!tsm_stream_level_pending(s)) break;
 *       rc = tsm_stream_feed(s, NULL, 0, err, sizeof err);
 *     }
 *   }
 */
/* Nonzero: tsm_stream_feed returns after each new level (the base, then each
 * batch), keeping the bytes after it for the next feed (which may be empty). */
void tsm_stream_stop_at_levels(tsm_stream* s, int on);
/* Nonzero when the last feed stopped at a level with bytes left to decode. */
int tsm_stream_level_pending(const tsm_stream* s);
/* Nonzero once the base mesh is whole and a refinement batch follows it. */
int tsm_stream_progressive(const tsm_stream* s);
/* Refinement batches applied so far (0 = the base). */
size_t tsm_stream_batches_done(const tsm_stream* s);
/* The encoder's error of the current level (the largest distance of a full-mesh
 * vertex from the level, in the mesh's units, as the file records it); -1 when
 * unknown (single-rate files, the base before the first batch's bytes are in). */
double tsm_stream_level_error(const tsm_stream* s);

/* Decoding a prefix of a progressive file: the finest level whose batches are
 * whole within the bytes (and within max_bytes when nonzero), stopping at the
 * first level whose error is at most max_error when max_error > 0. A
 * single-rate file decodes only whole; an error when even the base mesh is cut
 * off or a byte in use is damaged. partial, options and report may be NULL. */
typedef struct tsm_partial_options {
  uint64_t max_bytes; /* 0 = all the bytes given */
  double max_error;   /* <= 0: refine as far as the bytes go */
} tsm_partial_options;
typedef struct tsm_partial_report {
  uint64_t bytes_used; /* bytes of the file the level needed */
  double error;        /* the encoder's error of the level decoded */
  uint32_t batches;    /* refinement batches applied */
  int complete;        /* nonzero: the whole file was there and decoded */
} tsm_partial_report;
int tsm_decode_partial(const uint8_t* data, size_t size, const tsm_partial_options* partial,
                       const tsm_decode_options* options, tsm_mesh** out, tsm_partial_report* report, char* err,
                       size_t err_size);

size_t tsm_mesh_vertex_count(const tsm_mesh* mesh);
size_t tsm_mesh_face_count(const tsm_mesh* mesh);
size_t tsm_mesh_index_count(const tsm_mesh* mesh);
const float* tsm_mesh_positions(const tsm_mesh* mesh);      /* 3 * vertex_count */
const uint32_t* tsm_mesh_face_offsets(const tsm_mesh* mesh); /* face_count + 1 */
const uint32_t* tsm_mesh_indices(const tsm_mesh* mesh);      /* index_count */

/* ---- attributes ----------------------------------------------------------
 * Normals, colours, texture coordinates and other values per vertex, per face
 * or per face corner (tsm::Attribute in mesh.hpp). Values are always floats
 * here, components floats per value; the type says how they were stored (an
 * integer type holds integer values, a u8 colour is 0..255, and is coded
 * exactly; float ones are quantized: by default normals octahedral with 10
 * bits per axis, texture coordinates on a grid of 12 bits, colours 10 bits,
 * others 16 bits). The vertex domain has one value per vertex, the face domain
 * one per face; the corner domain has one index per face corner (in the order
 * of tsm_mesh_indices) naming one of its own values (seams, creases), values
 * possibly shared or unused.
 *
 *   for (size_t a = 0; a < tsm_mesh_attribute_count(m); ++a)
 *     if (tsm_mesh_attribute_kind(m, a) == TSM_KIND_TEXCOORD) {
 *       const float* uv = tsm_mesh_attribute_values(m, a);        (2 floats per value)
 *       const uint32_t* ix = tsm_mesh_attribute_indices(m, a);    (corner domain, else NULL)
 *     }
 *
 * The accessors take an attribute number 0..count-1; out of range (or a NULL
 * mesh) they return NULL, 0 or -1. Pointers stay valid until the mesh is
 * changed or freed (for a stream's mesh: until the next feed/finish/free). */
enum { TSM_KIND_GENERIC = 0, TSM_KIND_NORMAL = 1, TSM_KIND_COLOR = 2, TSM_KIND_TEXCOORD = 3 };
enum { TSM_DOMAIN_VERTEX = 0, TSM_DOMAIN_FACE = 1, TSM_DOMAIN_CORNER = 2 };
enum { TSM_TYPE_F32 = 0, TSM_TYPE_U8 = 1, TSM_TYPE_U16 = 2, TSM_TYPE_I32 = 3 };

size_t tsm_mesh_attribute_count(const tsm_mesh* mesh);
/* The attribute's name, NUL-terminated ("normal", "texcoord", "color" or the file's own name). */
const char* tsm_mesh_attribute_name(const tsm_mesh* mesh, size_t attribute);
int tsm_mesh_attribute_kind(const tsm_mesh* mesh, size_t attribute);       /* TSM_KIND_*, -1 out of range */
int tsm_mesh_attribute_domain(const tsm_mesh* mesh, size_t attribute);     /* TSM_DOMAIN_* */
int tsm_mesh_attribute_type(const tsm_mesh* mesh, size_t attribute);       /* TSM_TYPE_* */
int tsm_mesh_attribute_components(const tsm_mesh* mesh, size_t attribute); /* 1..4 */
/* Values (vertex domain: vertex_count, face domain: face_count, corner domain: any). */
size_t tsm_mesh_attribute_value_count(const tsm_mesh* mesh, size_t attribute);
const float* tsm_mesh_attribute_values(const tsm_mesh* mesh, size_t attribute); /* components * value_count */
/* Corner domain: index_count entries, one per face corner, each < value_count. Other domains: 0 and NULL. */
size_t tsm_mesh_attribute_index_count(const tsm_mesh* mesh, size_t attribute);
const uint32_t* tsm_mesh_attribute_indices(const tsm_mesh* mesh, size_t attribute);

/* Attaches an attribute to a mesh the caller owns (from tsm_mesh_create or
 * tsm_decode; not a stream's mesh), for tsm_encode. name is NUL-terminated;
 * kind, domain and type are TSM_KIND_*, TSM_DOMAIN_*, TSM_TYPE_*; values holds
 * components * value_count floats; indices (corner domain only, else NULL and
 * 0) one entry per face corner naming a value. The arrays are copied. Checked
 * against the mesh: sizes matching the domain (value_count == vertex_count or
 * face_count, index_count == the mesh's index_count, indices < value_count),
 * components 1..4 (3 for a normal, 2 for a texture coordinate, 3 or 4 for a
 * colour); on an error (TSM_INVALID_ARGUMENT and a message naming the
 * attribute) the mesh is left as it was. Values of an integer type must be
 * integers (|x| <= 2^30) and every value finite: tsm_encode checks those.
 * tsm_encode quantizes float attributes with the default bits above. */
int tsm_mesh_add_attribute(tsm_mesh* mesh, const char* name, int kind, int domain, int type, int components,
                           const float* values, size_t value_count, const uint32_t* indices, size_t index_count,
                           char* err, size_t err_size);

/* ---- metadata ------------------------------------------------------------
 * Entries the codec passes through unchanged (a glTF document's materials and
 * scenes under the key "gltf", say; tsm::MetadataEntry in mesh.hpp): byte
 * strings, keys of 1..255 bytes, unique. The key and value pointers are
 * followed by a NUL (not counted in *size), so text can be read as C strings. */
size_t tsm_mesh_metadata_count(const tsm_mesh* mesh);
/* Entry number 0..count-1; NULL (and *size 0) out of range. size may be NULL. */
const char* tsm_mesh_metadata_key(const tsm_mesh* mesh, size_t entry, size_t* size);
const uint8_t* tsm_mesh_metadata_value(const tsm_mesh* mesh, size_t entry, size_t* size);
/* Adds an entry (key of key_size bytes, 1..255, not used yet; value of
 * value_size bytes, value may be NULL when value_size is 0) to a mesh the
 * caller owns. The bytes are copied. */
int tsm_mesh_add_metadata(tsm_mesh* mesh, const char* key, size_t key_size, const uint8_t* value, size_t value_size,
                          char* err, size_t err_size);

void tsm_mesh_free(tsm_mesh* mesh);
void tsm_free(void* buffer);
const char* tsm_version(void);

#ifdef __cplusplus
}
#endif

#endif /* TSM_H_ */
