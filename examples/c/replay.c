/* replay.c: replays an attitude log through the RINS estimator's C library.
 *
 *   replay < trial.csv > trial.estimates.csv
 *
 * Reads the attitude log (docs/log-format.md) on standard input and writes the estimates CSV on
 * standard output, byte for byte what `host-sim estimate trial.csv --out -` writes: the numbers
 * are read by rins_parse_number and the rows written by rins_format_row, the same code host-sim
 * runs. Warnings and a summary go to standard error.
 *
 * The log as host-sim reads it: columns found by name in a header row (any order, others
 * ignored); spaces around names and cells, a UTF-8 byte-order mark and \r\n or \r line ends
 * tolerated; lines starting with '#' and blank lines skipped; a row with a blank, missing or
 * non-numeric cell skipped with a warning (at most 10 printed). Cells are plain: no CSV quoting.
 * A line longer than LINE_MAX_LEN bytes is an unreadable row.
 *
 * Exit status: 0 when the log was read to its end; 1 for a log without a usable header or a
 * library error. Builds with any C11 compiler: `bash scripts/c-example.sh` builds and runs it on
 * this machine and on a Cortex-M4F in QEMU. */

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "rins_estimator.h"

enum { LINE_MAX_LEN = 16384, MAX_WARNINGS = 10, COLUMNS = 7 };

static const char *const COLUMN_NAMES[COLUMNS] = {
    "time_s", "rotation_deg", "platform_deg", "latitude_deg", "heading_deg", "roll_deg", "pitch_deg",
};

/* The estimator's memory: static, aligned as the header asks. */
static _Alignas(RINS_ESTIMATOR_ALIGN) unsigned char estimator_memory[RINS_ESTIMATOR_SIZE];
static char line[LINE_MAX_LEN + 1];
static char row[RINS_ROW_MAX_LEN];

/* Reads one line of standard input into `line` (without its end: \n, \r\n or \r). Returns its
 * length, -1 at the end of the input, or -2 for a line longer than LINE_MAX_LEN (skipped). */
static long read_line(void) {
    static int pending = EOF; /* a byte read ahead after a \r */
    size_t len = 0;
    int too_long = 0;
    int c = pending != EOF ? pending : getchar();
    pending = EOF;
    if (c == EOF) {
        return -1;
    }
    while (c != EOF && c != '\n' && c != '\r') {
        if (len < LINE_MAX_LEN) {
            line[len++] = (char)c;
        } else {
            too_long = 1;
        }
        c = getchar();
    }
    if (c == '\r') {
        int next = getchar();
        if (next != '\n') {
            pending = next;
        }
    }
    line[len] = '\0';
    return too_long ? -2 : (long)len;
}

static int is_space(char c) {
    return c == ' ' || c == '\t' || c == '\n' || c == '\r' || c == '\f' || c == '\v';
}

/* The cells of a line: start and length of each, split at commas, spaces around them trimmed. */
typedef struct {
    const char *start;
    size_t len;
} Cell;

static size_t split(char *text, Cell *cells, size_t max_cells) {
    size_t n = 0;
    char *p = text;
    for (;;) {
        char *end = strchr(p, ',');
        size_t len = end ? (size_t)(end - p) : strlen(p);
        const char *s = p;
        while (len > 0 && is_space(*s)) {
            s++;
            len--;
        }
        while (len > 0 && is_space(s[len - 1])) {
            len--;
        }
        if (n < max_cells) {
            cells[n].start = s;
            cells[n].len = len;
        }
        n++;
        if (!end) {
            return n;
        }
        p = end + 1;
    }
}

static void fail(const char *what, RinsError error) {
    fprintf(stderr, "error: %s: %s\n", what, rins_error_name(error));
    exit(1);
}

int main(void) {
    enum { MAX_CELLS = 256 };
    static Cell cells[MAX_CELLS];
    size_t column[COLUMNS]; /* the cell index of each column */
    int have_header = 0;
    unsigned long line_no = 0, rows = 0, rejected = 0, skipped = 0;
    size_t written;
    RinsConfig config;
    RinsEstimator *estimator;
    RinsError e;
    long len;

    /* Whole blocks to the output, not a line at a time (each write is a trap under semihosting). */
    setvbuf(stdout, NULL, _IOFBF, 4096);

    e = rins_config_default(&config);
    if (e != RINS_ERROR_OK) {
        fail("rins_config_default", e);
    }
    e = rins_estimator_init(estimator_memory, sizeof estimator_memory, &config, &estimator);
    if (e != RINS_ERROR_OK) {
        fail("rins_estimator_init", e);
    }

    while ((len = read_line()) != -1) {
        size_t n;
        line_no++;
        if (len == -2) {
            if (have_header) {
                if (skipped++ < MAX_WARNINGS) {
                    fprintf(stderr, "warning: -:%lu: line longer than %d bytes\n", line_no, LINE_MAX_LEN);
                }
                continue;
            }
            fprintf(stderr, "error: -:%lu: header line longer than %d bytes\n", line_no, LINE_MAX_LEN);
            return 1;
        }
        if (line[0] == '#') {
            continue;
        }
        n = split(line, cells, MAX_CELLS);
        if (n == 1 && cells[0].len == 0) {
            continue; /* blank */
        }
        if (!have_header) {
            static const char BOM[] = "\xEF\xBB\xBF";
            size_t k, i;
            if (n > MAX_CELLS) {
                fprintf(stderr, "error: -:%lu: more than %d columns\n", line_no, MAX_CELLS);
                return 1;
            }
            if (cells[0].len >= 3 && memcmp(cells[0].start, BOM, 3) == 0) {
                cells[0].start += 3;
                cells[0].len -= 3;
            }
            for (k = 0; k < COLUMNS; k++) {
                size_t found = 0;
                for (i = 0; i < n; i++) {
                    if (cells[i].len == strlen(COLUMN_NAMES[k]) && memcmp(cells[i].start, COLUMN_NAMES[k], cells[i].len) == 0) {
                        column[k] = i;
                        found++;
                    }
                }
                if (found != 1) {
                    fprintf(stderr, "error: -:%lu: bad header: column \"%s\" %s\n", line_no, COLUMN_NAMES[k],
                            found ? "appears twice" : "is missing");
                    return 1;
                }
            }
            have_header = 1;
            e = rins_format_header(row, sizeof row, &written);
            if (e != RINS_ERROR_OK) {
                fail("rins_format_header", e);
            }
            fwrite(row, 1, written, stdout);
            continue;
        }
        {
            double value[COLUMNS];
            const char *problem = NULL;
            size_t k;
            RinsSample sample;
            RinsOutput output;
            for (k = 0; k < COLUMNS && !problem; k++) {
                size_t i = column[k];
                if (i >= n || i >= MAX_CELLS) {
                    problem = "short row";
                } else if (cells[i].len == 0) {
                    problem = "blank cell";
                } else if (rins_parse_number(cells[i].start, cells[i].len, &value[k]) != RINS_ERROR_OK) {
                    problem = "not a number";
                }
            }
            if (problem) {
                if (skipped++ < MAX_WARNINGS) {
                    fprintf(stderr, "warning: -:%lu: %s: %s\n", line_no, COLUMN_NAMES[k - 1], problem);
                }
                continue;
            }
            sample.time_s = value[0];
            sample.rotation_deg = value[1];
            sample.platform_deg = value[2];
            sample.latitude_deg = value[3];
            sample.heading_deg = value[4];
            sample.roll_deg = value[5];
            sample.pitch_deg = value[6];
            e = rins_estimator_step(estimator, &sample, &output);
            if (e == RINS_ERROR_SAMPLE_REJECTED) {
                rejected++;
            } else if (e != RINS_ERROR_OK) {
                fail("rins_estimator_step", e);
            }
            rows++;
            e = rins_format_row(&output, row, sizeof row, &written);
            if (e != RINS_ERROR_OK) {
                fail("rins_format_row", e);
            }
            fwrite(row, 1, written, stdout);
        }
    }
    if (!have_header) {
        fprintf(stderr, "error: -:%lu: no header, expected the columns time_s,rotation_deg,...\n", line_no + 1);
        return 1;
    }
    if (fflush(stdout) != 0) {
        fprintf(stderr, "error: cannot write the estimates\n");
        return 1;
    }
    fprintf(stderr, "%lu rows, %lu rejected by the estimator, %lu unreadable rows skipped\n", rows, rejected, skipped);
    return 0;
}
