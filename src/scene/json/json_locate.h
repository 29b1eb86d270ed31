/* Source positions inside JSON text. jansson does not record where values came from, so
 * loaders find them again by walking the raw text along a path of keys and indices. */
#ifndef CST_SCENE_JSON_JSON_LOCATE_H
#define CST_SCENE_JSON_JSON_LOCATE_H

#include <stdbool.h>
#include <stddef.h>

/* One step into a document: the member `key` of an object, or, when key is NULL, the
 * element `index` of an array. Keys are UTF-8 as decoded (escapes in the text match). */
typedef struct JsonPathStep {
    const char *key;
    size_t index;
} JsonPathStep;

/* 1-based line and column. Lines end at '\n'; columns count Unicode code points (UTF-8
 * lead bytes), a tab counting as one, the same convention as jansson's error positions. */
typedef struct JsonLocation {
    int line, column;
} JsonLocation;

typedef enum JsonLocateTarget {
    JSON_LOCATE_VALUE, /* the first character of the value at the path */
    JSON_LOCATE_KEY    /* the opening quote of the last step's key (last step must be a key) */
} JsonLocateTarget;

/* Finds the path in text[0, len). Returns true and fills *out, or false when the path is
 * not in the text (or the text is not JSON along the way). Any bytes are accepted and
 * nothing outside text[0, len) is read; no allocation, no recursion, so hostile input
 * costs at most O(len * depth) time. An empty path (depth 0) is the top-level value. */
bool json_locate(const char *text, size_t len, const JsonPathStep *path, int depth,
                 JsonLocateTarget target, JsonLocation *out);

/* Line and column of byte `offset` (clamped to len) under the convention above. */
JsonLocation json_offset_location(const char *text, size_t len, size_t offset);

#endif
