/*
 * The C ABI's smoke test (scripts/test_c.sh builds and runs it).
 *
 *   smoke full WORK          every call and every error path on the data in WORK
 *   smoke cycles N WORK      N create/free cycles of every handle, then a cancelled job
 *
 * WORK holds what scripts/test_c.sh made with the `tagsplat` program: data/ (a `tagsplat synth`
 * dataset, with ground-truth meshes/ and trajectories.csv), gt.pc2 + gt.obj (`tagsplat convert`
 * of data/meshes), train.toml (a short config). `full` writes c_out/ (a run to compare with the
 * CLI's cli_out/) and resume_out/ (a cancelled run, then resumed), which the script compares.
 * Oracles: the PC2 and OBJ files read here byte by byte, the synthetic trajectories, the bound
 * triangles' normals computed here, the header's macros, the CLI's output (in the script).
 */
#define _POSIX_C_SOURCE 200809L

#include "tagsplat.h"

#include <dlfcn.h>
#include <math.h>
#include <pthread.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

static int failures = 0;
static const char *work = NULL;

/* ---- checking ------------------------------------------------------------------------------ */

static const char *last_error(void) {
    static char message[4096];
    tagsplat_last_error(message, sizeof message);
    return message;
}

static void fail(int line, const char *what) {
    fprintf(stderr, "FAILED line %d: %s\n", line, what);
    failures++;
}

#define CHECK(cond) ((cond) ? (void)0 : fail(__LINE__, #cond))

/* `status` must be `want`. A failure's message must name the function it came from and contain
 * `part` (when not NULL): the argument or file concerned. */
static void expect(int line, const char *call, tagsplat_status status, tagsplat_status want,
                   const char *part) {
    const char *message = last_error();
    if (status != want) {
        fprintf(stderr, "FAILED line %d: %s\n  gave %s, expected %s: %s\n", line, call,
                tagsplat_status_name(status), tagsplat_status_name(want), message);
        failures++;
        return;
    }
    if (want == TAGSPLAT_STATUS_OK) {
        if (message[0] != '\0') fail(line, "a call that succeeded left a message");
        return;
    }
    if (strncmp(message, "tagsplat_", 9) != 0 || (part && !strstr(message, part))) {
        fprintf(stderr, "FAILED line %d: %s\n  message does not name '%s': %s\n", line, call,
                part ? part : "its function", message);
        failures++;
    }
}

#define OK(call) expect(__LINE__, #call, (call), TAGSPLAT_STATUS_OK, NULL)
#define FAILS(call, want, part) expect(__LINE__, #call, (call), (want), (part))

static const char *in_work(const char *name) {
    static char paths[8][1024];
    static int next = 0;
    char *path = paths[next++ % 8];
    snprintf(path, sizeof paths[0], "%s/%s", work, name);
    return path;
}

/* The whole file at `path` (NUL-terminated), or NULL; `*size` gets its length. */
static char *slurp(const char *path, size_t *size) {
    FILE *f = fopen(path, "rb");
    char *data = NULL;
    long n;
    if (!f) return NULL;
    if (fseek(f, 0, SEEK_END) == 0 && (n = ftell(f)) >= 0 && fseek(f, 0, SEEK_SET) == 0) {
        data = malloc((size_t)n + 1);
        if (data && fread(data, 1, (size_t)n, f) == (size_t)n) {
            data[n] = '\0';
            *size = (size_t)n;
        } else {
            free(data);
            data = NULL;
        }
    }
    fclose(f);
    return data;
}

/* Writes `text` to `path`; a failure fails the test. */
static void write_text(const char *path, const char *text) {
    FILE *f = fopen(path, "w");
    if (!f || fputs(text, f) < 0) fail(__LINE__, path);
    if (f) fclose(f);
}

static uint32_t le32(const unsigned char *p) {
    return (uint32_t)p[0] | (uint32_t)p[1] << 8 | (uint32_t)p[2] << 16 | (uint32_t)p[3] << 24;
}

/* ---- version, context, dataset ------------------------------------------------------------- */

static void test_version(void) {
    char expected[64];
    snprintf(expected, sizeof expected, "%d.%d.%d", TAGSPLAT_VERSION_MAJOR,
             TAGSPLAT_VERSION_MINOR, TAGSPLAT_VERSION_PATCH);
    CHECK(strcmp(tagsplat_version(), expected) == 0);
    CHECK(strcmp(tagsplat_version(), TAGSPLAT_VERSION_STRING) == 0);
    CHECK(strcmp(tagsplat_status_name(TAGSPLAT_STATUS_BAD_INPUT), "TAGSPLAT_STATUS_BAD_INPUT") == 0);
    CHECK(strcmp(tagsplat_status_name(12345), "unknown status") == 0);
}

static void test_context(tagsplat_context *ctx) {
    size_t needed = 0;
    char name[256], tiny[2];
    tagsplat_context *none = (tagsplat_context *)1;
    OK(tagsplat_context_device_name(ctx, NULL, 0, &needed));
    CHECK(needed > 1 && needed <= sizeof name);
    OK(tagsplat_context_device_name(ctx, name, sizeof name, NULL));
    CHECK(strlen(name) + 1 == needed);
    FAILS(tagsplat_context_device_name(ctx, tiny, sizeof tiny, &needed), TAGSPLAT_STATUS_BUFFER_TOO_SMALL, "buf");
    FAILS(tagsplat_context_create(NULL, 7, &none), TAGSPLAT_STATUS_BAD_INPUT, "validation");
    CHECK(none == NULL);
    FAILS(tagsplat_context_create("no such device", 0, &none), TAGSPLAT_STATUS_DEVICE, "no such device");
    FAILS(tagsplat_context_create(NULL, 0, NULL), TAGSPLAT_STATUS_BAD_INPUT, "out");
}

static void test_dataset(tagsplat_context *ctx) {
    tagsplat_dataset *dataset = NULL;
    size_t needed = 0;
    char small[8], *json;
    OK(tagsplat_dataset_open(ctx, in_work("data"), 0.0, 1, &dataset));
    OK(tagsplat_dataset_info_json(dataset, NULL, 0, &needed));
    json = malloc(needed);
    FAILS(tagsplat_dataset_info_json(dataset, small, sizeof small, NULL), TAGSPLAT_STATUS_BUFFER_TOO_SMALL, "needed");
    OK(tagsplat_dataset_info_json(dataset, json, needed, NULL));
    CHECK(strlen(json) + 1 == needed);
    /* `tagsplat synth --views 4 --frames 2` in scripts/test_c.sh. */
    CHECK(strstr(json, "\"frames\": 2") != NULL);
    CHECK(strstr(json, "\"views\": 8") != NULL);
    CHECK(strstr(json, "\"problems\": []") != NULL);
    free(json);
    OK(tagsplat_dataset_free(dataset));
    FAILS(tagsplat_dataset_open(ctx, in_work("no_data"), 0.0, 0, &dataset), TAGSPLAT_STATUS_BAD_INPUT, "no_data");
    CHECK(dataset == NULL);
    FAILS(tagsplat_dataset_open(ctx, NULL, 0.0, 0, &dataset), TAGSPLAT_STATUS_BAD_INPUT, "path");
    FAILS(tagsplat_dataset_open(NULL, in_work("data"), 0.0, 0, &dataset), TAGSPLAT_STATUS_INVALID_HANDLE, "context");
}

/* ---- sequences ----------------------------------------------------------------------------- */

/* The sequence read from data/meshes against gt.pc2 (positions, read here from its bytes) and
 * gt.obj (faces, from its `f a b c` lines), both written by `tagsplat convert`. */
static void test_sequence_read(void) {
    tagsplat_sequence *sequence = NULL;
    tagsplat_sequence_counts info;
    size_t pc2_size = 0, obj_size = 0, face = 0;
    unsigned char *pc2 = (unsigned char *)slurp(in_work("gt.pc2"), &pc2_size);
    char *obj = slurp(in_work("gt.obj"), &obj_size), *line;
    float *positions;
    uint32_t *faces;
    CHECK(pc2 != NULL && pc2_size > 32 && obj != NULL);
    if (!pc2 || !obj) return;
    OK(tagsplat_sequence_read(in_work("data/meshes"), &sequence));
    OK(tagsplat_sequence_info(sequence, &info));
    CHECK(info.vertices == le32(pc2 + 16) && info.frames == le32(pc2 + 28));
    CHECK(info.has_colors == 1);
    positions = malloc(info.frames * info.vertices * 3 * sizeof *positions);
    faces = malloc(info.faces * 3 * sizeof *faces);
    FAILS(tagsplat_sequence_positions(sequence, positions, 5), TAGSPLAT_STATUS_BUFFER_TOO_SMALL, "buf holds 5");
    FAILS(tagsplat_sequence_positions(sequence, NULL, 0), TAGSPLAT_STATUS_BUFFER_TOO_SMALL, "buf");
    OK(tagsplat_sequence_positions(sequence, positions, info.frames * info.vertices * 3));
    CHECK(pc2_size == 32 + info.frames * info.vertices * 12);
    CHECK(memcmp(positions, pc2 + 32, info.frames * info.vertices * 12) == 0);
    OK(tagsplat_sequence_faces(sequence, faces, info.faces * 3));
    for (line = strtok(obj, "\n"); line; line = strtok(NULL, "\n")) {
        unsigned a, b, c;
        if (sscanf(line, "f %u %u %u", &a, &b, &c) != 3) continue;
        CHECK(face < info.faces && faces[3 * face] == a - 1 && faces[3 * face + 1] == b - 1 &&
              faces[3 * face + 2] == c - 1);
        face++;
    }
    CHECK(face == info.faces);
    free(positions);
    free(faces);
    free(pc2);
    free(obj);
    OK(tagsplat_sequence_free(sequence));
    FAILS(tagsplat_sequence_read(in_work("missing"), &sequence), TAGSPLAT_STATUS_BAD_INPUT, "no such file");
    CHECK(sequence == NULL);
    FAILS(tagsplat_sequence_read(in_work("train.toml"), &sequence), TAGSPLAT_STATUS_BAD_INPUT, "not a sequence");
    FAILS(tagsplat_sequence_read(NULL, &sequence), TAGSPLAT_STATUS_BAD_INPUT, "path is NULL");
    FAILS(tagsplat_sequence_read("", &sequence), TAGSPLAT_STATUS_BAD_INPUT, "empty path");
    /* The read options reach the engine: a folder has no animations; the frame rate is checked. */
    FAILS(tagsplat_sequence_read_with(in_work("data/meshes"), "Run", 0.0, NULL, &sequence),
          TAGSPLAT_STATUS_BAD_INPUT, "--animation has no meaning for a folder");
    FAILS(tagsplat_sequence_read_with(in_work("data/meshes"), NULL, -5.0, NULL, &sequence),
          TAGSPLAT_STATUS_BAD_INPUT, "--fps -5");
    OK(tagsplat_sequence_read_with(in_work("data/meshes"), NULL, 30.0, NULL, &sequence));
    OK(tagsplat_sequence_free(sequence));
}

/* A tetrahedron over two frames: from arrays, copied back, written and read again as PC2 and as
 * a folder of PLY frames; every bad array refused. */
static void test_sequence_arrays(void) {
    const float positions[2][4][3] = {
        {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}},
        {{0, 0, 0.5f}, {1, 0, 0.5f}, {0, 1, 0.5f}, {0, 0, 1.5f}},
    };
    const uint32_t faces[4][3] = {{0, 2, 1}, {0, 1, 3}, {0, 3, 2}, {1, 2, 3}};
    const char *copies[2] = {"tet.pc2", "tet_frames"};
    float back[24], bad[24];
    uint32_t back_faces[12], bad_faces[12];
    tagsplat_sequence *sequence = NULL, *again = NULL;
    tagsplat_sequence_counts info;
    int i;
    OK(tagsplat_sequence_create(&positions[0][0][0], 2, 4, &faces[0][0], 4, &sequence));
    OK(tagsplat_sequence_info(sequence, &info));
    CHECK(info.frames == 2 && info.vertices == 4 && info.faces == 4 && info.has_colors == 0);
    OK(tagsplat_sequence_positions(sequence, back, 24));
    CHECK(memcmp(back, positions, sizeof back) == 0);
    OK(tagsplat_sequence_faces(sequence, back_faces, 12));
    CHECK(memcmp(back_faces, faces, sizeof faces) == 0);
    for (i = 0; i < 2; i++) {
        OK(tagsplat_sequence_write(sequence, in_work(copies[i]), TAGSPLAT_FRAME_FORMAT_PLY, 24.0));
        OK(tagsplat_sequence_read(in_work(copies[i]), &again));
        OK(tagsplat_sequence_positions(again, back, 24));
        CHECK(memcmp(back, positions, sizeof back) == 0);
        OK(tagsplat_sequence_faces(again, back_faces, 12));
        CHECK(memcmp(back_faces, faces, sizeof faces) == 0);
        OK(tagsplat_sequence_free(again));
    }
    FAILS(tagsplat_sequence_write(sequence, in_work("tet_frames"), TAGSPLAT_FRAME_FORMAT_OBJ, 24.0), TAGSPLAT_STATUS_BAD_INPUT, "already holds frame files");
    FAILS(tagsplat_sequence_write(sequence, in_work("x"), 9, 24.0), TAGSPLAT_STATUS_BAD_INPUT, "format");
    OK(tagsplat_sequence_free(sequence));
    memcpy(bad, positions, sizeof bad);
    bad[13] = (float)NAN;
    FAILS(tagsplat_sequence_create(bad, 2, 4, &faces[0][0], 4, &sequence), TAGSPLAT_STATUS_BAD_INPUT, "positions");
    CHECK(sequence == NULL);
    memcpy(bad_faces, faces, sizeof faces);
    bad_faces[7] = 4;
    FAILS(tagsplat_sequence_create(&positions[0][0][0], 2, 4, bad_faces, 4, &sequence), TAGSPLAT_STATUS_BAD_INPUT, "faces");
    FAILS(tagsplat_sequence_create(&positions[0][0][0], 0, 4, &faces[0][0], 4, &sequence), TAGSPLAT_STATUS_BAD_INPUT, "0 frames");
    FAILS(tagsplat_sequence_create(NULL, 2, 4, &faces[0][0], 4, &sequence), TAGSPLAT_STATUS_BAD_INPUT, "positions is NULL");
    FAILS(tagsplat_sequence_create(&positions[0][0][0], SIZE_MAX, SIZE_MAX, &faces[0][0], 4, &sequence), TAGSPLAT_STATUS_BAD_INPUT, "overflow");
}

/* ---- tracking ------------------------------------------------------------------------------ */

#define MAX_POINTS 64
#define MAX_FRAMES 16

/* data/trajectories.csv (`id,frame,x,y,z`): the synthetic ground truth of every tracked point. */
static size_t read_truth(double truth[MAX_POINTS][MAX_FRAMES][3], size_t *frames) {
    char ids[MAX_POINTS][64], id[64], line[512];
    size_t points = 0, i;
    unsigned frame;
    double x, y, z;
    FILE *f = fopen(in_work("data/trajectories.csv"), "r");
    *frames = 0;
    if (!f) return 0;
    while (fgets(line, sizeof line, f)) {
        if (sscanf(line, "%63[^,],%u,%lf,%lf,%lf", id, &frame, &x, &y, &z) != 5) continue;
        for (i = 0; i < points && strcmp(ids[i], id) != 0; i++) {
        }
        if (i == MAX_POINTS || frame >= MAX_FRAMES) continue;
        if (i == points) strcpy(ids[points++], id);
        truth[i][frame][0] = x, truth[i][frame][1] = y, truth[i][frame][2] = z;
        if (frame + 1 > *frames) *frames = frame + 1;
    }
    fclose(f);
    return points;
}

static void test_track_points(tagsplat_sequence *sequence) {
    static double truth[MAX_POINTS][MAX_FRAMES][3], start[MAX_POINTS + 1][3];
    static double paths[(MAX_POINTS + 1) * MAX_FRAMES * 3];
    tagsplat_binding bindings[MAX_POINTS + 1];
    size_t frames = 0, points = read_truth(truth, &frames), i, t, k, unbound[2];
    tagsplat_tracks *tracks = NULL;
    tagsplat_tracks_counts info;
    double worst = 0;
    CHECK(points >= 4 && frames == 2);
    for (i = 0; i < points; i++) memcpy(start[i], truth[i][0], sizeof start[i]);
    /* One more, far off the surface: listed as not bound. */
    start[points][0] = 100, start[points][1] = 100, start[points][2] = 100;
    OK(tagsplat_track_points(sequence, &start[0][0], points + 1, 0.01, &tracks));
    OK(tagsplat_tracks_info(tracks, &info));
    CHECK(info.frames == frames && info.points == points && info.unbound == 1 && info.max_distance > 0);
    OK(tagsplat_tracks_unbound(tracks, unbound, 2));
    CHECK(unbound[0] == points);
    FAILS(tagsplat_tracks_trajectories(tracks, paths, 3), TAGSPLAT_STATUS_BUFFER_TOO_SMALL, "needed");
    OK(tagsplat_tracks_trajectories(tracks, paths, points * frames * 3));
    OK(tagsplat_tracks_bindings(tracks, bindings, points));
    for (i = 0; i < points; i++) {
        double sum = bindings[i].barycentric[0] + bindings[i].barycentric[1] + bindings[i].barycentric[2];
        CHECK(bindings[i].query == i && fabs(sum - 1) < 1e-9 && bindings[i].distance < 1e-5);
        for (t = 0; t < frames; t++)
            for (k = 0; k < 3; k++) {
                double d = fabs(paths[(i * frames + t) * 3 + k] - truth[i][t][k]);
                worst = d > worst ? d : worst;
            }
    }
    /* The ground truth is Σ b·v(t) over f32 vertices, as tracking computes it. */
    if (!(worst < 1e-5)) fprintf(stderr, "worst trajectory error %g\n", worst);
    CHECK(worst < 1e-5);
    OK(tagsplat_tracks_free(tracks));
    start[1][2] = NAN;
    FAILS(tagsplat_track_points(sequence, &start[0][0], points, 0.01, &tracks), TAGSPLAT_STATUS_BAD_INPUT, "points[1]");
    CHECK(tracks == NULL);
    FAILS(tagsplat_track_points(sequence, &start[0][0], 1, NAN, &tracks), TAGSPLAT_STATUS_BAD_INPUT, "max_distance");
    FAILS(tagsplat_track_points(sequence, NULL, 3, 0.01, &tracks), TAGSPLAT_STATUS_BAD_INPUT, "points is NULL");
}

/* A camera 3 units before a surface point p, looking along +z through it: the pixel at the
 * principal point casts the ray x = p.x, y = p.y, which hits the surface there. */
static void test_track_pixels(tagsplat_sequence *sequence) {
    static double truth[MAX_POINTS][MAX_FRAMES][3];
    size_t frames = 0;
    double path[MAX_FRAMES * 3], pixel[2] = {32, 32}, nan_pixel[2] = {NAN, 1};
    tagsplat_camera camera = {64, 64, 50, 50, 32, 32, {1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1}};
    tagsplat_tracks *tracks = NULL;
    tagsplat_tracks_counts info;
    CHECK(read_truth(truth, &frames) > 0);
    camera.world_to_camera[3] = -truth[0][0][0];
    camera.world_to_camera[7] = -truth[0][0][1];
    camera.world_to_camera[11] = 3 - truth[0][0][2];
    OK(tagsplat_track_pixels(sequence, &camera, pixel, 1, &tracks));
    OK(tagsplat_tracks_info(tracks, &info));
    CHECK(info.points == 1 && info.unbound == 0);
    OK(tagsplat_tracks_trajectories(tracks, path, frames * 3));
    CHECK(fabs(path[0] - truth[0][0][0]) < 1e-6 && fabs(path[1] - truth[0][0][1]) < 1e-6);
    OK(tagsplat_tracks_free(tracks));
    FAILS(tagsplat_track_pixels(sequence, &camera, nan_pixel, 1, &tracks), TAGSPLAT_STATUS_BAD_INPUT, "pixels[0]");
    camera.fx = NAN;
    FAILS(tagsplat_track_pixels(sequence, &camera, pixel, 1, &tracks), TAGSPLAT_STATUS_BAD_INPUT, "camera");
    camera.fx = 50;
    camera.world_to_camera[0] = 2;
    FAILS(tagsplat_track_pixels(sequence, &camera, pixel, 1, &tracks), TAGSPLAT_STATUS_BAD_INPUT, "rigid");
    FAILS(tagsplat_track_pixels(sequence, NULL, pixel, 1, &tracks), TAGSPLAT_STATUS_BAD_INPUT, "camera is NULL");
}

/* The unit normal and the tangent along the first edge (a -> b, its normal part removed) of
 * triangle (a, b, c), as docs/conventions.md and engine/track/frame.rs define them, computed here
 * in double from the sequence's positions. */
static void triangle_frame(const float *a, const float *b, const float *c, double n[3],
                           double t[3]) {
    double e1[3], e2[3], length, along = 0;
    int k;
    for (k = 0; k < 3; k++) e1[k] = (double)b[k] - a[k], e2[k] = (double)c[k] - a[k];
    n[0] = e1[1] * e2[2] - e1[2] * e2[1];
    n[1] = e1[2] * e2[0] - e1[0] * e2[2];
    n[2] = e1[0] * e2[1] - e1[1] * e2[0];
    length = sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
    for (k = 0; k < 3; k++) n[k] /= length, along += e1[k] * n[k];
    for (k = 0; k < 3; k++) t[k] = e1[k] - along * n[k];
    length = sqrt(t[0] * t[0] + t[1] * t[1] + t[2] * t[2]);
    for (k = 0; k < 3; k++) t[k] /= length;
}

/* The points of data/trajectories.csv at frame 0, tracked; `*points` and `*frames` get the
 * counts. */
static tagsplat_tracks *track_truth(tagsplat_sequence *sequence, size_t *points, size_t *frames) {
    static double truth[MAX_POINTS][MAX_FRAMES][3], start[MAX_POINTS][3];
    tagsplat_tracks *tracks = NULL;
    size_t i;
    *points = read_truth(truth, frames);
    for (i = 0; i < *points; i++) memcpy(start[i], truth[i][0], sizeof start[i]);
    OK(tagsplat_track_points(sequence, &start[0][0], *points, 0.01, &tracks));
    return tracks;
}

/* Orientation frames, polygons and clock on data/meshes, a folder of PLY frames: no clock (24
 * frames per second from frame 0), its triangles are its faces. The normals and tangents are
 * each bound triangle's own, computed here from the positions. */
static void test_track_frames(tagsplat_sequence *sequence) {
    static double normals[MAX_POINTS * MAX_FRAMES * 3], tangents[MAX_POINTS * MAX_FRAMES * 3];
    static unsigned char held[MAX_POINTS * MAX_FRAMES];
    tagsplat_binding bindings[MAX_POINTS];
    tagsplat_sequence_counts counts;
    tagsplat_tracks_counts info;
    size_t points = 0, frames = 0, i, t, k, n;
    tagsplat_tracks *tracks = track_truth(sequence, &points, &frames);
    double times[MAX_FRAMES], worst = 0, normal[3], tangent[3];
    float *positions;
    uint32_t *faces;
    OK(tagsplat_tracks_info(tracks, &info));
    CHECK(info.points == points && info.fps == 24 && info.start_frame == 0);
    OK(tagsplat_tracks_times(tracks, times, frames));
    for (t = 0; t < frames; t++) CHECK(times[t] == t / 24.0);
    n = points * frames;
    FAILS(tagsplat_tracks_normals(tracks, normals, 3), TAGSPLAT_STATUS_BUFFER_TOO_SMALL, "needed");
    FAILS(tagsplat_tracks_orientation_held(tracks, held, n - 1), TAGSPLAT_STATUS_BUFFER_TOO_SMALL, "needed");
    OK(tagsplat_tracks_normals(tracks, normals, n * 3));
    OK(tagsplat_tracks_tangents(tracks, tangents, n * 3));
    OK(tagsplat_tracks_orientation_held(tracks, held, n));
    OK(tagsplat_tracks_bindings(tracks, bindings, points));
    OK(tagsplat_sequence_info(sequence, &counts));
    positions = malloc(counts.frames * counts.vertices * 3 * sizeof *positions);
    faces = malloc(counts.faces * 3 * sizeof *faces);
    OK(tagsplat_sequence_positions(sequence, positions, counts.frames * counts.vertices * 3));
    OK(tagsplat_sequence_faces(sequence, faces, counts.faces * 3));
    for (i = 0; i < points; i++) {
        const uint32_t *face = faces + 3 * bindings[i].face;
        CHECK(bindings[i].polygon == bindings[i].face);
        for (t = 0; t < frames; t++) {
            const float *frame = positions + t * counts.vertices * 3;
            const double *got_n = normals + (i * frames + t) * 3, *got_t = tangents + (i * frames + t) * 3;
            triangle_frame(frame + 3 * face[0], frame + 3 * face[1], frame + 3 * face[2], normal, tangent);
            CHECK(held[i * frames + t] == 0);
            for (k = 0; k < 3; k++) {
                worst = fmax(worst, fabs(got_n[k] - normal[k]));
                worst = fmax(worst, fabs(got_t[k] - tangent[k]));
            }
        }
    }
    if (!(worst < 1e-12)) fprintf(stderr, "worst orientation difference %g\n", worst);
    CHECK(worst < 1e-12);
    free(positions);
    free(faces);
    OK(tagsplat_tracks_free(tracks));
}

/* Two tracks of the same points must agree bit for bit: trajectories and normals. */
static void expect_same_tracks(int line, tagsplat_tracks *a, tagsplat_tracks *b, size_t values) {
    static double x[MAX_POINTS * MAX_FRAMES * 3], y[MAX_POINTS * MAX_FRAMES * 3];
    expect(line, "tagsplat_tracks_trajectories", tagsplat_tracks_trajectories(a, x, values), TAGSPLAT_STATUS_OK, NULL);
    expect(line, "tagsplat_tracks_trajectories", tagsplat_tracks_trajectories(b, y, values), TAGSPLAT_STATUS_OK, NULL);
    if (memcmp(x, y, values * sizeof *x) != 0) fail(line, "trajectories differ");
    expect(line, "tagsplat_tracks_normals", tagsplat_tracks_normals(a, x, values), TAGSPLAT_STATUS_OK, NULL);
    expect(line, "tagsplat_tracks_normals", tagsplat_tracks_normals(b, y, values), TAGSPLAT_STATUS_OK, NULL);
    if (memcmp(x, y, values * sizeof *x) != 0) fail(line, "normals differ");
}

/* The GLB at `path` is a glTF 2 container of its own size with a node named "0" and an
 * animation. */
static void expect_pins(int line, const char *path) {
    size_t size = 0;
    unsigned char *glb = (unsigned char *)slurp(path, &size);
    if (!glb || size < 20 || memcmp(glb, "glTF", 4) != 0 || le32(glb + 4) != 2 || le32(glb + 8) != size) {
        fail(line, "not a glTF 2 binary of its own length");
    } else {
        uint32_t length = le32(glb + 12);
        char *json = malloc(length + 1);
        memcpy(json, glb + 20, length);
        json[length] = '\0';
        if (!strstr(json, "\"name\":\"0\"") || !strstr(json, "\"animations\"")) fail(line, "no node 0 or no animation");
        free(json);
    }
    free(glb);
}

/* Bindings given back (written to a file and read again, as arrays, as vertex ids) track what
 * the points did, bit for bit; the files `tagsplat track` writes are written; bad bindings are
 * refused naming the point, the file and the line. */
static void test_track_bindings(tagsplat_sequence *sequence) {
    static double paths[MAX_POINTS * MAX_FRAMES * 3], barycentric[MAX_POINTS][3];
    tagsplat_binding bindings[MAX_POINTS], again_bindings[MAX_POINTS];
    uint32_t faces[MAX_POINTS], vertices[3] = {0, 3, 5}, far_face = 99999;
    size_t points = 0, frames = 0, i, t, k, size = 0;
    tagsplat_tracks *tracks = track_truth(sequence, &points, &frames), *again = NULL;
    tagsplat_sequence_counts counts;
    const double nan_weights[3] = {0.5, NAN, 0.5}, unnormalised[3] = {0.5, 0.5, 0.5};
    float *positions;
    char *text;
    OK(tagsplat_tracks_bindings(tracks, bindings, points));
    OK(tagsplat_tracks_write_bindings(tracks, in_work("c_bindings.csv")));
    OK(tagsplat_track_bindings_file(sequence, in_work("c_bindings.csv"), &again));
    expect_same_tracks(__LINE__, tracks, again, points * frames * 3);
    OK(tagsplat_tracks_bindings(again, again_bindings, points));
    for (i = 0; i < points; i++) {
        CHECK(again_bindings[i].query == i && again_bindings[i].face == bindings[i].face);
        CHECK(memcmp(again_bindings[i].barycentric, bindings[i].barycentric, sizeof barycentric[0]) == 0);
        faces[i] = bindings[i].face;
        memcpy(barycentric[i], bindings[i].barycentric, sizeof barycentric[i]);
    }
    OK(tagsplat_tracks_free(again));
    OK(tagsplat_track_bindings(sequence, faces, &barycentric[0][0], points, &again));
    expect_same_tracks(__LINE__, tracks, again, points * frames * 3);
    OK(tagsplat_tracks_free(again));
    /* A bindings file's points keep its ids; points given as arrays are named by their index. */
    write_text(in_work("named.csv"), "id,face,u,v,w\nnose,0,1,0,0\ntail_tip,1,0,1,0\n");
    OK(tagsplat_track_bindings_file(sequence, in_work("named.csv"), &again));
    OK(tagsplat_tracks_point_id(again, 1, NULL, 0, &size));
    CHECK(size == sizeof "tail_tip");
    {
        char id[16];
        OK(tagsplat_tracks_point_id(again, 1, id, sizeof id, NULL));
        CHECK(strcmp(id, "tail_tip") == 0);
        FAILS(tagsplat_tracks_point_id(again, 0, id, 4, NULL), TAGSPLAT_STATUS_BUFFER_TOO_SMALL, "buf holds 4 values, 5 are needed");
        FAILS(tagsplat_tracks_point_id(again, 2, id, sizeof id, NULL), TAGSPLAT_STATUS_BAD_INPUT, "point: 2 is not below the 2 bound points");
        OK(tagsplat_tracks_point_id(tracks, 0, id, sizeof id, NULL));
        CHECK(strcmp(id, "0") == 0);
    }
    OK(tagsplat_tracks_free(again));
    /* A vertex's track is its own positions, exactly. */
    OK(tagsplat_track_vertices(sequence, vertices, 3, &again));
    OK(tagsplat_tracks_trajectories(again, paths, 3 * frames * 3));
    OK(tagsplat_sequence_info(sequence, &counts));
    positions = malloc(counts.frames * counts.vertices * 3 * sizeof *positions);
    OK(tagsplat_sequence_positions(sequence, positions, counts.frames * counts.vertices * 3));
    for (i = 0; i < 3; i++)
        for (t = 0; t < frames; t++)
            for (k = 0; k < 3; k++)
                CHECK(paths[(i * frames + t) * 3 + k] == positions[(t * counts.vertices + vertices[i]) * 3 + k]);
    free(positions);
    OK(tagsplat_tracks_free(again));
    /* The program's files: the CSV has a row per point per frame after its header. */
    OK(tagsplat_tracks_write_csv(tracks, in_work("c_tracks.csv")));
    OK(tagsplat_tracks_write_json(tracks, in_work("c_tracks.json")));
    OK(tagsplat_tracks_write_pins(tracks, in_work("c_pins.glb"), NULL));
    expect_pins(__LINE__, in_work("c_pins.glb"));
    text = slurp(in_work("c_tracks.csv"), &size);
    CHECK(text && strncmp(text, "id,frame,x,y,z,nx,ny,nz,tx,ty,tz,time,fps,start_frame\n", 54) == 0);
    for (i = 0, k = 0; text && text[i]; i++) k += text[i] == '\n';
    CHECK(k == 1 + points * frames);
    free(text);
    text = slurp(in_work("c_tracks.json"), &size);
    CHECK(text && strstr(text, "\"fps\": 24.0") && strstr(text, "\"normal\": ["));
    free(text);
    FAILS(tagsplat_tracks_write_csv(tracks, in_work("no_such_folder/t.csv")), TAGSPLAT_STATUS_BAD_INPUT, "no_such_folder");
    FAILS(tagsplat_tracks_write_pins(tracks, in_work("p.glb"), "+q"), TAGSPLAT_STATUS_BAD_INPUT, "from_up: '+q'");
    FAILS(tagsplat_tracks_write_json(tracks, NULL), TAGSPLAT_STATUS_BAD_INPUT, "path is NULL");
    OK(tagsplat_tracks_free(tracks));
    /* Bad bindings. */
    FAILS(tagsplat_track_bindings(sequence, &far_face, unnormalised, 1, &again), TAGSPLAT_STATUS_BAD_INPUT, "binding of point 0: face 99999 is out of range");
    CHECK(again == NULL);
    FAILS(tagsplat_track_bindings(sequence, faces, unnormalised, 1, &again), TAGSPLAT_STATUS_BAD_INPUT, "sums to 1.5, not 1");
    FAILS(tagsplat_track_bindings(sequence, faces, nan_weights, 1, &again), TAGSPLAT_STATUS_BAD_INPUT, "barycentric[0]");
    FAILS(tagsplat_track_bindings(sequence, NULL, unnormalised, 1, &again), TAGSPLAT_STATUS_BAD_INPUT, "faces is NULL");
    vertices[1] = (uint32_t)counts.vertices;
    FAILS(tagsplat_track_vertices(sequence, vertices, 3, &again), TAGSPLAT_STATUS_BAD_INPUT, "binding of point 1: vertex");
    FAILS(tagsplat_track_bindings_file(sequence, in_work("missing.csv"), &again), TAGSPLAT_STATUS_BAD_INPUT, "missing.csv");
    write_text(in_work("bad_bindings.csv"), "id,face,u,v,w\nok,0,1,0,0\nfar,99999,1,0,0\n");
    FAILS(tagsplat_track_bindings_file(sequence, in_work("bad_bindings.csv"), &again), TAGSPLAT_STATUS_BAD_INPUT, "bad_bindings.csv: line 3: face 99999 is out of range");
}

/* A Z-up USD strip of two quads, fanned into triangles 2q and 2q + 1, on scene frames 10 to 12
 * at 24 per second, beside a second mesh: read with a mesh chosen, its points carry their
 * quads as polygons and the file's clock. */
static const char strip_usda[] =
    "#usda 1.0\n(\n    startTimeCode = 10\n    endTimeCode = 12\n    timeCodesPerSecond = 24\n"
    "    upAxis = \"Z\"\n)\n\ndef Mesh \"Strip\"\n{\n    int[] faceVertexCounts = [4, 4]\n"
    "    int[] faceVertexIndices = [0, 1, 4, 3, 1, 2, 5, 4]\n    point3f[] points.timeSamples = {\n"
    "        10: [(0, 0, 0), (1, 0, 0), (2, 0, 0), (0, 1, 0), (1, 1, 0), (2, 1, 0)],\n"
    "        11: [(0, 0, 0), (1, 0, 0.2), (2, 0, 0.6), (0, 1, 0.1), (1, 1, 0.3), (2, 1, 0.7)],\n"
    "        12: [(0, 0, 0.1), (1, 0.1, 0.5), (2, 0, 1.2), (0, 1, 0.2), (1, 1.1, 0.6), (2, 1, 1.4)],\n"
    "    }\n}\n\ndef Mesh \"Other\"\n{\n    int[] faceVertexCounts = [3]\n"
    "    int[] faceVertexIndices = [0, 1, 2]\n    point3f[] points = [(0, 0, 0), (1, 0, 0), (0, 1, 0)]\n}\n";

static void test_track_polygons(void) {
    const double points[4][3] = {{0.3, 0.6, 0}, {1.7, 0.2, 0}, {1.2, 0.9, 0}, {0.8, 0.1, 0}};
    const char *path = in_work("strip.usda");
    tagsplat_sequence *strip = NULL;
    tagsplat_tracks *tracks = NULL;
    tagsplat_tracks_counts info;
    tagsplat_binding bindings[4];
    double times[3];
    size_t i;
    write_text(path, strip_usda);
    FAILS(tagsplat_sequence_read(path, &strip), TAGSPLAT_STATUS_FILE_FORMAT, "/Strip, /Other");
    OK(tagsplat_sequence_read_with(path, NULL, 0.0, "/Strip", &strip));
    OK(tagsplat_track_points(strip, &points[0][0], 4, 0.01, &tracks));
    OK(tagsplat_tracks_info(tracks, &info));
    CHECK(info.points == 4 && info.frames == 3);
    CHECK(fabs(info.fps - 24) < 1e-9 && fabs(info.start_frame - 10) < 1e-9);
    OK(tagsplat_tracks_times(tracks, times, 3));
    for (i = 0; i < 3; i++) CHECK(fabs(times[i] - (10 + i) / 24.0) < 1e-12);
    OK(tagsplat_tracks_bindings(tracks, bindings, 4));
    for (i = 0; i < 4; i++) CHECK(bindings[i].polygon == bindings[i].face / 2);
    CHECK(bindings[0].polygon == 0 && bindings[1].polygon == 1);
    OK(tagsplat_tracks_write_pins(tracks, in_work("strip_pins.glb"), NULL));
    expect_pins(__LINE__, in_work("strip_pins.glb"));
    OK(tagsplat_tracks_free(tracks));
    OK(tagsplat_sequence_free(strip));
}

/* ---- jobs ---------------------------------------------------------------------------------- */

/* What a progress callback saw, and when it cancels: at the first report of frame `cancel_at`
 * in stage FRAME or FIT (-1: never). `hold` keeps the job inside its first report until released. */
struct watch {
    long cancel_at;
    uint64_t reports, last_update;
    int out_of_order, saw_loss;
    pthread_mutex_t lock;
    pthread_cond_t changed;
    int held, hold;
};

static void watch_init(struct watch *w, long cancel_at, int hold) {
    memset(w, 0, sizeof *w);
    w->cancel_at = cancel_at;
    w->hold = hold;
    pthread_mutex_init(&w->lock, NULL);
    pthread_cond_init(&w->changed, NULL);
}

static void watch_release(struct watch *w) {
    pthread_mutex_lock(&w->lock);
    while (!w->held) pthread_cond_wait(&w->changed, &w->lock);
    w->hold = 0;
    pthread_cond_broadcast(&w->changed);
    pthread_mutex_unlock(&w->lock);
}

static void watch_destroy(struct watch *w) {
    pthread_mutex_destroy(&w->lock);
    pthread_cond_destroy(&w->changed);
}

static int on_progress(const tagsplat_progress *p, void *user) {
    struct watch *w = user;
    pthread_mutex_lock(&w->lock);
    w->held = 1;
    pthread_cond_broadcast(&w->changed);
    while (w->hold) pthread_cond_wait(&w->changed, &w->lock);
    w->reports++;
    w->out_of_order |= p->update <= w->last_update;
    w->last_update = p->update;
    w->saw_loss |= p->stage == TAGSPLAT_JOB_STAGE_FRAME && !isnan(p->loss);
    pthread_mutex_unlock(&w->lock);
    return (p->stage == TAGSPLAT_JOB_STAGE_FRAME || p->stage == TAGSPLAT_JOB_STAGE_FIT) &&
           (long)p->frame == w->cancel_at;
}

/* A training run's description with its own copies of the paths (in_work's are reused). */
struct train {
    char data[1024], out[1024], config[1024];
    tagsplat_train_desc desc;
};

static tagsplat_train_desc *train_desc(struct train *t, const char *out) {
    snprintf(t->data, sizeof t->data, "%s", in_work("data"));
    snprintf(t->out, sizeof t->out, "%s", in_work(out));
    snprintf(t->config, sizeof t->config, "%s", in_work("train.toml"));
    memset(&t->desc, 0, sizeof t->desc);
    t->desc.data = t->data;
    t->desc.out = t->out;
    t->desc.config_path = t->config;
    return &t->desc;
}

/* Waits for `job` and checks how it ended. */
static void finish(int line, tagsplat_job *job, tagsplat_status want, const char *part) {
    int finished = 0;
    expect(line, "tagsplat_job_wait", tagsplat_job_wait(job, -1.0, &finished), TAGSPLAT_STATUS_OK, NULL);
    if (!finished) fail(line, "tagsplat_job_wait returned before the end");
    expect(line, "tagsplat_job_result", tagsplat_job_result(job), want, part);
}

/* The run the script compares with the CLI's: config from a file, every frame. */
static void test_train(tagsplat_context *ctx) {
    struct train paths;
    tagsplat_train_desc *desc = train_desc(&paths, "c_out");
    tagsplat_job *job = NULL;
    tagsplat_progress progress;
    struct watch w;
    size_t needed = 0;
    char *report;
    int finished = 0;
    watch_init(&w, -1, 0);
    OK(tagsplat_train_start(ctx, desc, on_progress, &w, &job));
    finish(__LINE__, job, TAGSPLAT_STATUS_OK, NULL);
    OK(tagsplat_job_poll(job, &progress, &finished));
    CHECK(finished == 1 && progress.update == w.reports && w.reports > 10);
    CHECK(progress.stage == TAGSPLAT_JOB_STAGE_FRAME && progress.frames_end == 2 && progress.elapsed_s > 0);
    CHECK(!w.out_of_order && w.saw_loss);
    OK(tagsplat_job_report_json(job, NULL, 0, &needed));
    report = malloc(needed);
    OK(tagsplat_job_report_json(job, report, needed, NULL));
    CHECK(strstr(report, "\"resumed_frames\": []") != NULL);
    free(report);
    OK(tagsplat_job_result(job));
    OK(tagsplat_job_free(job));
    watch_destroy(&w);
}

/* A run cancelled by its callback when frame 1 starts, then resumed into the same folder from
 * a config given as text: the script compares the result with the CLI's uninterrupted run.
 * While the first is held inside a report, it has not finished, and a second run into its
 * folder is refused. */
static void test_cancel_and_resume(tagsplat_context *ctx) {
    struct train paths;
    tagsplat_train_desc *desc = train_desc(&paths, "resume_out");
    tagsplat_job *job = NULL, *rival = NULL;
    struct watch w;
    size_t size = 0;
    char *toml = slurp(in_work("train.toml"), &size);
    watch_init(&w, 1, 1);
    OK(tagsplat_train_start(ctx, desc, on_progress, &w, &job));
    pthread_mutex_lock(&w.lock);
    while (!w.held) pthread_cond_wait(&w.changed, &w.lock);
    pthread_mutex_unlock(&w.lock);
    FAILS(tagsplat_job_result(job), TAGSPLAT_STATUS_NOT_FINISHED, "has not finished");
    FAILS(tagsplat_job_report_json(job, NULL, 0, NULL), TAGSPLAT_STATUS_NOT_FINISHED, "has not finished");
    OK(tagsplat_train_start(ctx, desc, NULL, NULL, &rival));
    finish(__LINE__, rival, TAGSPLAT_STATUS_BAD_INPUT, "resume_out");
    OK(tagsplat_job_free(rival));
    watch_release(&w);
    finish(__LINE__, job, TAGSPLAT_STATUS_CANCELLED, "cancelled");
    FAILS(tagsplat_job_report_json(job, NULL, 0, NULL), TAGSPLAT_STATUS_CANCELLED, "cancelled");
    OK(tagsplat_job_free(job));
    watch_destroy(&w);
    desc->config_path = NULL;
    desc->config_toml = toml;
    OK(tagsplat_train_start(ctx, desc, NULL, NULL, &job));
    finish(__LINE__, job, TAGSPLAT_STATUS_OK, NULL);
    OK(tagsplat_job_free(job));
    free(toml);
}

/* A run held inside its first report, cancelled by tagsplat_job_cancel from this thread,
 * released: it ends cancelled at that report. */
static void cancelled_job(tagsplat_context *ctx, const char *out) {
    struct train paths;
    tagsplat_train_desc *desc = train_desc(&paths, out);
    tagsplat_job *job = NULL;
    struct watch w;
    watch_init(&w, -1, 1);
    OK(tagsplat_train_start(ctx, desc, on_progress, &w, &job));
    OK(tagsplat_job_cancel(job));
    watch_release(&w);
    finish(__LINE__, job, TAGSPLAT_STATUS_CANCELLED, "cancelled");
    OK(tagsplat_job_cancel(job));
    OK(tagsplat_job_free(job));
    watch_destroy(&w);
}

/* A job cancelled from this thread, and one freed while it runs. */
static void test_cancel_call(tagsplat_context *ctx) {
    struct train paths;
    tagsplat_train_desc *desc = train_desc(&paths, "freed_out");
    tagsplat_job *job = NULL;
    cancelled_job(ctx, "cancel_out");
    OK(tagsplat_train_start(ctx, desc, NULL, NULL, &job));
    OK(tagsplat_job_free(job));
}

static void test_job_errors(tagsplat_context *ctx) {
    struct train paths;
    tagsplat_train_desc *desc = train_desc(&paths, "error_out");
    tagsplat_fit_desc fit;
    tagsplat_job *job = NULL;
    int finished = 0;
    desc->config_path = NULL;
    desc->config_toml = "[canonical]\niterations = -3\n";
    FAILS(tagsplat_train_start(ctx, desc, NULL, NULL, &job), TAGSPLAT_STATUS_BAD_INPUT, "iterations");
    CHECK(job == NULL);
    desc->config_toml = "no_such_key = 1\n";
    FAILS(tagsplat_train_start(ctx, desc, NULL, NULL, &job), TAGSPLAT_STATUS_BAD_INPUT, "no_such_key");
    desc->config_path = in_work("train.toml");
    FAILS(tagsplat_train_start(ctx, desc, NULL, NULL, &job), TAGSPLAT_STATUS_BAD_INPUT, "not both");
    desc->config_toml = NULL;
    desc->config_path = in_work("missing.toml");
    FAILS(tagsplat_train_start(ctx, desc, NULL, NULL, &job), TAGSPLAT_STATUS_BAD_INPUT, "missing.toml");
    desc->config_path = NULL;
    desc->data = NULL;
    FAILS(tagsplat_train_start(ctx, desc, NULL, NULL, &job), TAGSPLAT_STATUS_BAD_INPUT, "desc.data");
    FAILS(tagsplat_train_start(ctx, NULL, NULL, NULL, &job), TAGSPLAT_STATUS_BAD_INPUT, "desc");
    desc->data = in_work("no_data");
    OK(tagsplat_train_start(ctx, desc, NULL, NULL, &job));
    finish(__LINE__, job, TAGSPLAT_STATUS_BAD_INPUT, "no_data");
    OK(tagsplat_job_free(job));
    desc->data = in_work("data");
    desc->frame_start = 1;
    desc->frame_end = 9;
    OK(tagsplat_train_start(ctx, desc, NULL, NULL, &job));
    finish(__LINE__, job, TAGSPLAT_STATUS_BAD_INPUT, "frames 1..9");
    OK(tagsplat_job_free(job));
    memset(&fit, 0, sizeof fit);
    fit.data = in_work("data");
    fit.frame = 5;
    OK(tagsplat_fit_start(ctx, &fit, NULL, NULL, &job));
    finish(__LINE__, job, TAGSPLAT_STATUS_BAD_INPUT, NULL);
    OK(tagsplat_job_free(job));
    FAILS(tagsplat_job_wait(job, -1.0, &finished), TAGSPLAT_STATUS_INVALID_HANDLE, "job");
}

/* A short fit: its report, and a callback that cancels. */
static void test_fit(tagsplat_context *ctx) {
    tagsplat_fit_desc fit;
    tagsplat_job *job = NULL;
    struct watch w;
    size_t needed = 0;
    memset(&fit, 0, sizeof fit);
    fit.data = in_work("data");
    fit.out = in_work("fit_out");
    fit.config_toml = "iterations = 20\n";
    OK(tagsplat_fit_start(ctx, &fit, NULL, NULL, &job));
    finish(__LINE__, job, TAGSPLAT_STATUS_OK, NULL);
    OK(tagsplat_job_report_json(job, NULL, 0, &needed));
    CHECK(needed > 2);
    OK(tagsplat_job_free(job));
    watch_init(&w, 0, 0);
    OK(tagsplat_fit_start(ctx, &fit, on_progress, &w, &job));
    finish(__LINE__, job, TAGSPLAT_STATUS_CANCELLED, "cancelled");
    CHECK(w.reports == 1);
    OK(tagsplat_job_free(job));
    watch_destroy(&w);
}

/* ---- handles ------------------------------------------------------------------------------- */

static void test_handles(tagsplat_context *ctx) {
    const float positions[9] = {0, 0, 0, 1, 0, 0, 0, 1, 0};
    const uint32_t faces[3] = {0, 1, 2};
    tagsplat_sequence *sequence = NULL;
    tagsplat_sequence_counts info;
    OK(tagsplat_context_free(NULL));
    OK(tagsplat_dataset_free(NULL));
    OK(tagsplat_sequence_free(NULL));
    OK(tagsplat_tracks_free(NULL));
    OK(tagsplat_job_free(NULL));
    OK(tagsplat_sequence_create(positions, 1, 3, faces, 1, &sequence));
    /* A handle of one kind passed as another. */
    FAILS(tagsplat_tracks_info((tagsplat_tracks *)sequence, NULL), TAGSPLAT_STATUS_INVALID_HANDLE, "is a tagsplat_sequence, not a tagsplat_tracks");
    FAILS(tagsplat_context_free((tagsplat_context *)sequence), TAGSPLAT_STATUS_INVALID_HANDLE, "not a tagsplat_context");
    FAILS(tagsplat_sequence_info(sequence, NULL), TAGSPLAT_STATUS_BAD_INPUT, "info is NULL");
    OK(tagsplat_sequence_free(sequence));
    /* Used after free, freed twice, never made. */
    FAILS(tagsplat_sequence_info(sequence, &info), TAGSPLAT_STATUS_INVALID_HANDLE, "freed already");
    FAILS(tagsplat_sequence_free(sequence), TAGSPLAT_STATUS_INVALID_HANDLE, "sequence");
    FAILS(tagsplat_sequence_info((tagsplat_sequence *)&info, &info), TAGSPLAT_STATUS_INVALID_HANDLE, "never created");
    FAILS(tagsplat_sequence_info(NULL, &info), TAGSPLAT_STATUS_INVALID_HANDLE, "sequence is NULL");
    (void)ctx;
}

static int run_full(void) {
    tagsplat_context *ctx = NULL;
    tagsplat_sequence *sequence = NULL;
    uint64_t messages = 1;
    test_version();
    OK(tagsplat_context_create(NULL, -1, &ctx));
    if (!ctx) return 1;
    test_context(ctx);
    test_dataset(ctx);
    test_sequence_read();
    test_sequence_arrays();
    OK(tagsplat_sequence_read(in_work("data/meshes"), &sequence));
    test_track_points(sequence);
    test_track_pixels(sequence);
    test_track_frames(sequence);
    test_track_bindings(sequence);
    OK(tagsplat_sequence_free(sequence));
    test_track_polygons();
    test_handles(ctx);
    test_job_errors(ctx);
    test_train(ctx);
    test_cancel_and_resume(ctx);
    test_cancel_call(ctx);
    test_fit(ctx);
    OK(tagsplat_context_validation_messages(ctx, &messages));
    CHECK(messages == 0);
    OK(tagsplat_context_free(ctx));
    return failures;
}

/* ---- leak cycles --------------------------------------------------------------------------- */

static int run_cycles(long n) {
    const float positions[9] = {0, 0, 0, 1, 0, 0, 0, 1, 0};
    const uint32_t faces[3] = {0, 1, 2};
    const double point[3] = {0.25, 0.25, 0};
    const uint32_t vertex[1] = {2};
    struct train paths;
    tagsplat_train_desc *desc = train_desc(&paths, "cycles_out");
    tagsplat_context *ctx = NULL, *other = NULL;
    tagsplat_dataset *dataset = NULL;
    tagsplat_sequence *sequence = NULL, *read = NULL;
    tagsplat_tracks *tracks = NULL;
    tagsplat_job *job = NULL;
    long i;
    OK(tagsplat_context_create(NULL, -1, &ctx));
    for (i = 0; i < n && failures == 0; i++) {
        OK(tagsplat_context_create(NULL, 0, &other));
        OK(tagsplat_context_free(other));
        OK(tagsplat_dataset_open(ctx, in_work("data"), 0.0, 0, &dataset));
        OK(tagsplat_dataset_free(dataset));
        OK(tagsplat_sequence_read(in_work("data/meshes"), &read));
        OK(tagsplat_sequence_free(read));
        OK(tagsplat_sequence_create(positions, 1, 3, faces, 1, &sequence));
        OK(tagsplat_track_points(sequence, point, 1, 0.01, &tracks));
        OK(tagsplat_tracks_free(tracks));
        OK(tagsplat_track_vertices(sequence, vertex, 1, &tracks));
        OK(tagsplat_tracks_write_pins(tracks, in_work("cycle_pins.glb"), NULL));
        OK(tagsplat_tracks_free(tracks));
        OK(tagsplat_sequence_free(sequence));
        /* A job whose run fails at once: the thread, the handle and the failure are freed. */
        desc->data = in_work("no_data");
        OK(tagsplat_train_start(ctx, desc, NULL, NULL, &job));
        finish(__LINE__, job, TAGSPLAT_STATUS_BAD_INPUT, "no_data");
        OK(tagsplat_job_free(job));
        /* Failed calls leave their messages behind them, freed on the next call. */
        FAILS(tagsplat_sequence_read(in_work("missing"), &read), TAGSPLAT_STATUS_BAD_INPUT, "missing");
    }
    cancelled_job(ctx, "cycles_cancelled");
    OK(tagsplat_context_free(ctx));
    return failures;
}

/* Opens each library of the colon-separated `list` once more, so the Vulkan loader's dlclose
 * does not unmap it: the leak checkers can then see what its globals hold and name its frames
 * (scripts/test_c.sh passes lavapipe and the validation layer). RTLD_LOCAL: nothing of theirs is
 * interposed on the loader's symbols. */
static void keep_loaded(const char *list) {
    char copy[4096], *name;
    snprintf(copy, sizeof copy, "%s", list ? list : "");
    for (name = strtok(copy, ":"); name; name = strtok(NULL, ":"))
        if (!dlopen(name, RTLD_NOW | RTLD_LOCAL)) fprintf(stderr, "cannot keep %s loaded: %s\n", name, dlerror());
}

int main(int argc, char **argv) {
    int result;
    keep_loaded(getenv("SMOKE_KEEP_LOADED"));
    if (argc == 3 && strcmp(argv[1], "full") == 0) {
        work = argv[2];
        result = run_full();
    } else if (argc == 4 && strcmp(argv[1], "cycles") == 0) {
        work = argv[3];
        result = run_cycles(atol(argv[2]));
    } else {
        fprintf(stderr, "usage: %s full WORK | %s cycles N WORK\n", argv[0], argv[0]);
        return 2;
    }
    fprintf(stderr, "%s: %d failure(s)\n", argv[1], failures);
    return result == 0 ? 0 : 1;
}
