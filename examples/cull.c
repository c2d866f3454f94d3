/*
 * Culls a tincull hierarchy from C through the cull-capi library (crates/cull-capi).
 *
 *   cc examples/cull.c -I crates/cull-capi/include target/release/libtincull_cull.a -lpthread -ldl -lm -o cull
 *   ./cull FILE.tch safe|thesis|stewart|lloyd-egbert X,Y,Z[,YAW,FOV] ...
 *
 * For every eye it prints one line, the ranges to draw as `start-end` pairs (half-open), the same ranges as
 * `tincull cull FILE.tch --method M --eye X,Y,Z --yaw YAW --fov FOV --json` (YAW 0 and FOV 360 when not given).
 * The file is loaded twice, once by path and once from a memory buffer, and both cullers must agree.
 */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "tincull_cull.h"

static int fail(const char *what, int32_t status) {
    fprintf(stderr, "error: %s failed (status %d): %s\n", what, (int)status, tc_last_error());
    return 1;
}

static unsigned char *read_file(const char *path, size_t *len) {
    FILE *f = fopen(path, "rb");
    if (!f) return NULL;
    fseek(f, 0, SEEK_END);
    long n = ftell(f);
    if (n < 0) {
        fclose(f);
        return NULL;
    }
    fseek(f, 0, SEEK_SET);
    unsigned char *buf = malloc(n > 0 ? (size_t)n : 1);
    if (buf && fread(buf, 1, (size_t)n, f) != (size_t)n) {
        free(buf);
        buf = NULL;
    }
    fclose(f);
    *len = (size_t)n;
    return buf;
}

int main(int argc, char **argv) {
    if (argc < 4) {
        fprintf(stderr, "usage: %s FILE.tch safe|thesis|stewart|lloyd-egbert X,Y,Z[,YAW,FOV] ...\n", argv[0]);
        return 2;
    }
    if ((tc_abi_version() >> 16) != (TC_ABI_VERSION >> 16)) {
        fprintf(stderr, "error: library ABI %u.%u, header %u.%u\n", tc_abi_version() >> 16,
                tc_abi_version() & 0xffff, TC_ABI_VERSION >> 16, TC_ABI_VERSION & 0xffff);
        return 1;
    }
    uint32_t method;
    if (strcmp(argv[2], "safe") == 0) method = TC_METHOD_SAFE;
    else if (strcmp(argv[2], "thesis") == 0) method = TC_METHOD_THESIS;
    else if (strcmp(argv[2], "stewart") == 0) method = TC_METHOD_STEWART;
    else if (strcmp(argv[2], "lloyd-egbert") == 0) method = TC_METHOD_LLOYD_EGBERT;
    else {
        fprintf(stderr, "error: unknown method %s: expected safe, thesis, stewart or lloyd-egbert\n", argv[2]);
        return 2;
    }

    TcCuller *by_path = NULL, *by_buffer = NULL;
    int32_t st = tc_load_path(argv[1], method, &by_path);
    if (st != TC_OK) return fail("tc_load_path", st);
    size_t len = 0;
    unsigned char *bytes = read_file(argv[1], &len);
    if (!bytes) {
        fprintf(stderr, "error: cannot read %s\n", argv[1]);
        return 1;
    }
    st = tc_load_buffer(bytes, len, method, &by_buffer);
    free(bytes);
    if (st != TC_OK) return fail("tc_load_buffer", st);

    TcInfo info;
    st = tc_info(by_path, &info);
    if (st != TC_OK) return fail("tc_info", st);
    fprintf(stderr, "%u triangles, %u nodes, %u sectors, origin %.3f %.3f %.3f\n", info.triangles, info.nodes,
            info.sectors, info.origin[0], info.origin[1], info.origin[2]);

    /* Start small to exercise TC_ERR_BUFFER_TOO_SMALL, then grow to what the library asks for. */
    size_t capacity = 1;
    TcRange *ranges = malloc(capacity * sizeof *ranges);
    TcRange *check = malloc(info.max_ranges * sizeof *check);
    if (!ranges || !check) {
        fprintf(stderr, "error: out of memory\n");
        return 1;
    }
    for (int a = 3; a < argc; a++) {
        double v[5] = {0, 0, 0, 0, 360};
        int n = sscanf(argv[a], "%lf,%lf,%lf,%lf,%lf", &v[0], &v[1], &v[2], &v[3], &v[4]);
        if (n != 3 && n != 5) {
            fprintf(stderr, "error: eye %s: expected X,Y,Z or X,Y,Z,YAW,FOV\n", argv[a]);
            return 2;
        }
        size_t count = 0;
        st = tc_cull(by_path, v, v[3], v[4], ranges, capacity, &count);
        if (st == TC_ERR_BUFFER_TOO_SMALL) {
            capacity = count;
            TcRange *grown = realloc(ranges, capacity * sizeof *ranges);
            if (!grown) {
                fprintf(stderr, "error: out of memory\n");
                return 1;
            }
            ranges = grown;
            st = tc_cull(by_path, v, v[3], v[4], ranges, capacity, &count);
        }
        if (st != TC_OK) return fail("tc_cull", st);
        size_t count2 = 0;
        st = tc_cull(by_buffer, v, v[3], v[4], check, info.max_ranges, &count2);
        if (st != TC_OK) return fail("tc_cull (buffer)", st);
        if (count2 != count || memcmp(check, ranges, count * sizeof *ranges) != 0) {
            fprintf(stderr, "error: the cullers loaded by path and from memory disagree\n");
            return 1;
        }
        TcStats stats;
        st = tc_stats(by_path, &stats);
        if (st != TC_OK) return fail("tc_stats", st);
        for (size_t i = 0; i < count; i++) printf("%s%u-%u", i ? " " : "", ranges[i].start, ranges[i].end);
        printf("\n");
        fprintf(stderr, "eye %s: %u of %u triangles drawn in %u ranges, %u nodes tested\n", argv[a],
                stats.triangles_drawn, info.triangles, stats.ranges, stats.nodes_tested);
    }

    /* Errors come back as codes with a message, never as a crash. */
    TcCuller *none = NULL;
    st = tc_load_buffer((const uint8_t *)"not a hierarchy", 15, method, &none);
    if (st != TC_ERR_FORMAT || none != NULL || strlen(tc_last_error()) == 0) {
        fprintf(stderr, "error: a bad buffer gave status %d\n", (int)st);
        return 1;
    }
    free(ranges);
    free(check);
    tc_free(by_path);
    tc_free(by_buffer);
    tc_free(NULL);
    return 0;
}
