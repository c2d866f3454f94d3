/*
 * Culls a tincull hierarchy from C through the cull-capi library (crates/cull-capi).
 *
 *   cc examples/cull.c -I crates/cull-capi/include target/release/libtincull_cull.a -lpthread -ldl -lm -o cull
 *   ./cull [--columns N] [--work-budget N] FILE.tch safe|thesis|stewart|lloyd-egbert X,Y,Z[,YAW,FOV] ...
 *
 * For every eye it prints one line, the ranges to draw as `start-end` pairs (half-open), the same ranges as
 * `tincull cull FILE.tch --method M --eye X,Y,Z --yaw YAW --fov FOV --json` (YAW 0 and FOV 360 when not given), with
 * `--columns` and `--work-budget` set through tc_set_params as `tincull cull` takes them.
 * The file is loaded twice, once by path and once from a memory buffer, and both cullers must agree (so it must be
 * a regular file: a named pipe would be read once). On standard error it describes the hierarchy and its mesh
 * (tc_mesh: what a renderer uploads) and, per eye, what is drawn and the lowest point of it (read from the mesh
 * through the ranges, as a renderer draws them).
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
    /* Leading options: the culler's run-time parameters, over the defaults. */
    TcParams params;
    if (tc_default_params(&params) != TC_OK) return fail("tc_default_params", TC_ERR_NULL);
    int first = 1, set = 0;
    while (first + 1 < argc && strncmp(argv[first], "--", 2) == 0) {
        char *end = NULL;
        unsigned long v = strtoul(argv[first + 1], &end, 10);
        if (*argv[first + 1] == '\0' || *end != '\0' || v > UINT32_MAX) {
            fprintf(stderr, "error: %s %s: expected a whole number\n", argv[first], argv[first + 1]);
            return 2;
        }
        if (strcmp(argv[first], "--columns") == 0) params.columns_per_face = (uint32_t)v;
        else if (strcmp(argv[first], "--work-budget") == 0) params.work_budget = (uint32_t)v;
        else {
            fprintf(stderr, "error: unknown option %s: expected --columns or --work-budget\n", argv[first]);
            return 2;
        }
        set = 1;
        first += 2;
    }
    if (argc - first < 3) {
        fprintf(stderr,
                "usage: %s [--columns N] [--work-budget N] FILE.tch safe|thesis|stewart|lloyd-egbert X,Y,Z[,YAW,FOV] ...\n",
                argv[0]);
        return 2;
    }
    const char *file = argv[first], *name = argv[first + 1];
    if ((tc_abi_version() >> 16) != (TC_ABI_VERSION >> 16)) {
        fprintf(stderr, "error: library ABI %u.%u, header %u.%u\n", tc_abi_version() >> 16,
                tc_abi_version() & 0xffff, TC_ABI_VERSION >> 16, TC_ABI_VERSION & 0xffff);
        return 1;
    }
    uint32_t method;
    if (strcmp(name, "safe") == 0) method = TC_METHOD_SAFE;
    else if (strcmp(name, "thesis") == 0) method = TC_METHOD_THESIS;
    else if (strcmp(name, "stewart") == 0) method = TC_METHOD_STEWART;
    else if (strcmp(name, "lloyd-egbert") == 0) method = TC_METHOD_LLOYD_EGBERT;
    else {
        fprintf(stderr, "error: unknown method %s: expected safe, thesis, stewart or lloyd-egbert\n", name);
        return 2;
    }

    TcCuller *by_path = NULL, *by_buffer = NULL;
    int32_t st = tc_load_path(file, method, &by_path);
    if (st != TC_OK) return fail("tc_load_path", st);
    size_t len = 0;
    unsigned char *bytes = read_file(file, &len);
    if (!bytes) {
        fprintf(stderr, "error: cannot read %s\n", file);
        return 1;
    }
    st = tc_load_buffer(bytes, len, method, &by_buffer);
    free(bytes);
    if (st != TC_OK) return fail("tc_load_buffer", st);
    if (set) {
        st = tc_set_params(by_path, &params);
        if (st != TC_OK) return fail("tc_set_params", st);
        st = tc_set_params(by_buffer, &params);
        if (st != TC_OK) return fail("tc_set_params (buffer)", st);
    }

    TcInfo info;
    st = tc_info(by_path, &info);
    if (st != TC_OK) return fail("tc_info", st);
    fprintf(stderr, "%u triangles, %u nodes, %u sectors, origin %.3f %.3f %.3f\n", info.triangles, info.nodes,
            info.sectors, info.origin[0], info.origin[1], info.origin[2]);
    TcMesh mesh;
    st = tc_mesh(by_path, &mesh);
    if (st != TC_OK) return fail("tc_mesh", st);
    if (mesh.triangles != info.triangles || mesh.vertices != info.vertices) {
        fprintf(stderr, "error: tc_mesh and tc_info disagree on the counts\n");
        return 1;
    }
    if (mesh.triangles > 0) {
        const uint32_t *t = mesh.indices;
        fprintf(stderr, "mesh: %u vertices, %u triangles, the first %u %u %u\n", mesh.vertices, mesh.triangles, t[0],
                t[1], t[2]);
    }

    /* Start small to exercise TC_ERR_BUFFER_TOO_SMALL, then grow to what the library asks for. */
    size_t capacity = 1;
    TcRange *ranges = malloc(capacity * sizeof *ranges);
    TcRange *check = malloc(info.max_ranges * sizeof *check);
    if (!ranges || !check) {
        fprintf(stderr, "error: out of memory\n");
        return 1;
    }
    for (int a = first + 2; a < argc; a++) {
        double v[5] = {0, 0, 0, 0, 360};
        /* %n records where the third and the fifth number end: the whole argument must be read, nothing after. */
        int end3 = -1, end5 = -1;
        int n = sscanf(argv[a], "%lf,%lf,%lf%n,%lf,%lf%n", &v[0], &v[1], &v[2], &end3, &v[3], &v[4], &end5);
        size_t len = strlen(argv[a]);
        int whole = (n == 3 && end3 >= 0 && (size_t)end3 == len) || (n == 5 && end5 >= 0 && (size_t)end5 == len);
        if (!whole) {
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
        TcWork work;
        st = tc_work(by_path, &work);
        if (st != TC_OK) return fail("tc_work", st);
        for (size_t i = 0; i < count; i++) printf("%s%u-%u", i ? " " : "", ranges[i].start, ranges[i].end);
        printf("\n");
        /* The ranges index the mesh's triangles: the lowest vertex drawn, as a renderer would reach it. */
        double lowest = 0;
        int any = 0;
        for (size_t i = 0; i < count; i++)
            for (uint32_t t = ranges[i].start; t < ranges[i].end; t++)
                for (int k = 0; k < 3; k++) {
                    double z = mesh.positions[3 * (size_t)mesh.indices[3 * (size_t)t + k] + 2];
                    if (!any || z < lowest) lowest = z;
                    any = 1;
                }
        fprintf(stderr, "eye %s: %u of %u triangles drawn in %u ranges, %u nodes tested, %u work units", argv[a],
                stats.triangles_drawn, info.triangles, stats.ranges, stats.nodes_tested, work.work);
        if (any) fprintf(stderr, ", lowest drawn vertex at z %.3f", lowest);
        fprintf(stderr, "\n");
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
