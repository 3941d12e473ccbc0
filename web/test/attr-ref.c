/* The native reference for the browser test's attribute check: decodes a
 * .tsm file with the C API (libcodec/include/tsm/tsm.h) and prints, as JSON,
 * the counts and, per attribute, its description and the FNV-1a (32-bit)
 * checksums of the bytes of its values (little-endian floats) and corner
 * indices; per metadata entry its key and the checksum of its value. The
 * browser decoder must give the same. Plain C99: it also shows tsm.h is.
 * web/test/browser.mjs compiles it against the native library:
 *   cc -std=c99 -pedantic -Wall -Wextra -Werror -Ilibcodec/include web/test/attr-ref.c \
 *      build/release/libcodec/libtsm.a -lstdc++ -lzstd -lxxhash -lm -lpthread -o attr-ref
 *   attr-ref FILE.tsm
 */
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "tsm/tsm.h"

static uint32_t fnv1a(const void* data, size_t size) {
  const unsigned char* b = (const unsigned char*)data;
  uint32_t h = 0x811c9dc5u;
  size_t i;
  for (i = 0; i < size; ++i) {
    h ^= b[i];
    h *= 0x01000193u;
  }
  return h;
}

/* A JSON string of n bytes (names and keys are printable in the test files). */
static void json_string(const char* s, size_t n) {
  size_t i;
  putchar('"');
  for (i = 0; i < n; ++i) {
    unsigned char c = (unsigned char)s[i];
    if (c == '"' || c == '\\') printf("\\%c", c);
    else if (c < 0x20) printf("\\u%04x", c);
    else putchar(c);
  }
  putchar('"');
}

int main(int argc, char** argv) {
  static const char* kinds[] = {"generic", "normal", "color", "texcoord"};
  static const char* domains[] = {"vertex", "face", "corner"};
  static const char* types[] = {"f32", "u8", "u16", "i32"};
  FILE* f;
  unsigned char* bytes;
  long size;
  tsm_mesh* mesh = NULL;
  char err[512];
  size_t i, n;
  if (argc != 2) {
    fprintf(stderr, "usage: attr-ref FILE.tsm\n");
    return 2;
  }
  f = fopen(argv[1], "rb");
  if (!f || fseek(f, 0, SEEK_END) != 0 || (size = ftell(f)) < 0 || fseek(f, 0, SEEK_SET) != 0) {
    fprintf(stderr, "attr-ref: cannot read %s\n", argv[1]);
    return 1;
  }
  bytes = (unsigned char*)malloc(size ? (size_t)size : 1);
  if (!bytes || fread(bytes, 1, (size_t)size, f) != (size_t)size) {
    fprintf(stderr, "attr-ref: cannot read %s\n", argv[1]);
    return 1;
  }
  fclose(f);
  if (tsm_decode(bytes, (size_t)size, NULL, &mesh, err, sizeof err) != TSM_OK) {
    fprintf(stderr, "attr-ref: %s: %s\n", argv[1], err);
    return 1;
  }
  printf("{\"vertexCount\": %lu, \"faceCount\": %lu, \"cornerCount\": %lu, \"attributes\": [",
         (unsigned long)tsm_mesh_vertex_count(mesh), (unsigned long)tsm_mesh_face_count(mesh),
         (unsigned long)tsm_mesh_index_count(mesh));
  n = tsm_mesh_attribute_count(mesh);
  for (i = 0; i < n; ++i) {
    const char* name = tsm_mesh_attribute_name(mesh, i);
    int components = tsm_mesh_attribute_components(mesh, i);
    size_t values = tsm_mesh_attribute_value_count(mesh, i);
    printf("%s\n  {\"name\": ", i ? "," : "");
    json_string(name, strlen(name));
    printf(", \"kind\": \"%s\", \"domain\": \"%s\", \"type\": \"%s\", \"components\": %d, \"valueCount\": %lu",
           kinds[tsm_mesh_attribute_kind(mesh, i)], domains[tsm_mesh_attribute_domain(mesh, i)],
           types[tsm_mesh_attribute_type(mesh, i)], components, (unsigned long)values);
    printf(", \"valuesHash\": \"%08lx\"",
           (unsigned long)fnv1a(tsm_mesh_attribute_values(mesh, i), values * (size_t)components * sizeof(float)));
    if (tsm_mesh_attribute_indices(mesh, i))
      printf(", \"indicesHash\": \"%08lx\"", (unsigned long)fnv1a(tsm_mesh_attribute_indices(mesh, i),
                                                                  tsm_mesh_attribute_index_count(mesh, i) * 4));
    else
      printf(", \"indicesHash\": null");
    printf("}");
  }
  printf("%s], \"metadata\": [", n ? "\n" : "");
  n = tsm_mesh_metadata_count(mesh);
  for (i = 0; i < n; ++i) {
    size_t key_size = 0, value_size = 0;
    const char* key = tsm_mesh_metadata_key(mesh, i, &key_size);
    const uint8_t* value = tsm_mesh_metadata_value(mesh, i, &value_size);
    printf("%s{\"key\": ", i ? ", " : "");
    json_string(key, key_size);
    printf(", \"valueHash\": \"%08lx\"}", (unsigned long)fnv1a(value, value_size));
  }
  printf("]}\n");
  tsm_mesh_free(mesh);
  free(bytes);
  return 0;
}
