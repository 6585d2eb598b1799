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
 * ignored; names matched in any case, a run of spaces and underscores standing for one underscore:
 * `Time S` is time_s); the separator the one of ',', ';' and tab that splits the header into the
 * most cells; the time in seconds (time_s), milliseconds (time_ms) or ISO 8601 / RFC 3339 UTC
 * (time_utc; the first of the three present is used; a cell of any of them that is a date and
 * time is read as one); spaces around names and cells, a UTF-8 byte-order mark and \r\n or \r
 * line ends tolerated; lines starting with '#' and blank lines skipped; a row with a blank,
 * missing or unreadable cell skipped with a warning (at most 10 printed). Cells are plain: no CSV
 * quoting. A date and time is read in the form YYYY-MM-DD, 'T' or a space, hh:mm:ss, an optional
 * fraction of up to 9 digits, then 'Z', an offset +hh:mm / -hh:mm, or nothing (UTC), from 1970
 * on; host-sim's date parser accepts more forms, which this program skips as unreadable rows.
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

/* The time columns, in the order one is chosen when a log has several. */
enum TimeUnit { SECONDS, MILLISECONDS, UTC };
static const char *const TIME_NAMES[3] = {"time_s", "time_ms", "time_utc"};

/* The separators a log may use; the one that splits the header into the most cells is used. */
static const char SEPARATORS[3] = {',', ';', '\t'};

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

/* The cells of a line: start and length of each, split at the separator, spaces around them
 * trimmed. */
typedef struct {
    const char *start;
    size_t len;
} Cell;

static size_t split(char *text, char separator, Cell *cells, size_t max_cells) {
    size_t n = 0;
    char *p = text;
    for (;;) {
        char *end = strchr(p, separator);
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

/* The separator of a header line: the one of SEPARATORS it holds most of (the first on a tie). */
static char separator_of(const char *text) {
    size_t counts[3] = {0, 0, 0}, i, best = 0;
    for (; *text; text++) {
        for (i = 0; i < 3; i++) {
            counts[i] += *text == SEPARATORS[i];
        }
    }
    for (i = 1; i < 3; i++) {
        if (counts[i] > counts[best]) {
            best = i;
        }
    }
    return SEPARATORS[best];
}

/* Whether a header cell names `name`: compared in lower case, a run of spaces and underscores
 * standing for one underscore (`Time S`, `TIME_S` and `time  s` are time_s). */
static int names(const Cell *cell, const char *name) {
    size_t i = 0;
    const char *n = name;
    while (i < cell->len) {
        char c = cell->start[i];
        if (c == ' ' || c == '_') {
            while (i < cell->len && (cell->start[i] == ' ' || cell->start[i] == '_')) {
                i++;
            }
            c = '_';
        } else {
            i++;
            if (c >= 'A' && c <= 'Z') {
                c = (char)(c - 'A' + 'a');
            }
        }
        if (*n != c) {
            return 0;
        }
        n++;
    }
    return *n == '\0';
}

/* The digits cell[at..at+count] as a number; -1 if any is not a digit. */
static long digits(const char *s, size_t count) {
    long v = 0;
    size_t i;
    for (i = 0; i < count; i++) {
        if (s[i] < '0' || s[i] > '9') {
            return -1;
        }
        v = v * 10 + (s[i] - '0');
    }
    return v;
}

/* Whether a cell is a date (YYYY-MM-DD...) rather than a number, as host-sim judges it. */
static int looks_like_date(const Cell *cell) {
    return cell->len >= 10 && digits(cell->start, 4) >= 0 && cell->start[4] == '-' && cell->start[7] == '-';
}

/* Days from 1970-01-01 to a civil date (proleptic Gregorian). */
static long long days_from_civil(long y, long m, long d) {
    long era, yoe, doy, doe;
    y -= m <= 2;
    era = (y >= 0 ? y : y - 399) / 400;
    yoe = y - era * 400;
    doy = (153 * (m + (m > 2 ? -3 : 9)) + 2) / 5 + d - 1;
    doe = yoe * 365 + yoe / 4 - yoe / 100 + doy;
    return (long long)era * 146097 + doe - 719468;
}

/* A date and time (see the head of this file) as Unix seconds, exactly as host-sim makes them:
 * whole seconds plus the nanoseconds times 1e-9. Returns 0 when the cell is not one. */
static int parse_utc(const Cell *cell, double *unix_s) {
    static const int DAYS_IN_MONTH[12] = {31, 29, 31, 30, 31, 30, 31, 31, 30, 31, 30, 31};
    const char *s = cell->start;
    size_t len = cell->len, at = 19;
    long y, mo, d, h, mi, sec, nanos = 0, scale = 100000000;
    long long seconds, offset_s = 0;
    if (len < 19 || s[4] != '-' || s[7] != '-' || (s[10] != 'T' && s[10] != 't' && s[10] != ' ') || s[13] != ':' ||
        s[16] != ':') {
        return 0;
    }
    y = digits(s, 4);
    mo = digits(s + 5, 2);
    d = digits(s + 8, 2);
    h = digits(s + 11, 2);
    mi = digits(s + 14, 2);
    sec = digits(s + 17, 2);
    if (y < 1970 || mo < 1 || mo > 12 || d < 1 || d > DAYS_IN_MONTH[mo - 1] || h < 0 || h > 23 || mi < 0 || mi > 59 ||
        sec < 0 || sec > 59 || (mo == 2 && d == 29 && !((y % 4 == 0 && y % 100 != 0) || y % 400 == 0))) {
        return 0;
    }
    if (at < len && (s[at] == '.' || s[at] == ',')) {
        size_t first = ++at;
        while (at < len && s[at] >= '0' && s[at] <= '9') {
            if (at - first >= 9) {
                return 0;
            }
            nanos += (s[at] - '0') * scale;
            scale /= 10;
            at++;
        }
        if (at == first) {
            return 0;
        }
    }
    if (at < len && (s[at] == 'Z' || s[at] == 'z')) {
        at++;
    } else if (at < len && (s[at] == '+' || s[at] == '-')) {
        long oh, om;
        if (len - at != 6 || s[at + 3] != ':' || (oh = digits(s + at + 1, 2)) < 0 || (om = digits(s + at + 4, 2)) < 0 ||
            oh > 23 || om > 59) {
            return 0;
        }
        offset_s = (oh * 3600 + om * 60) * (s[at] == '-' ? -1 : 1);
        at = len;
    }
    if (at != len) {
        return 0;
    }
    seconds = days_from_civil(y, mo, d) * 86400 + h * 3600 + mi * 60 + sec - offset_s;
    if (seconds < 0) {
        return 0;
    }
    *unix_s = (double)seconds + (double)nanos * 1e-9;
    return 1;
}

/* One time cell as seconds: a date and time, or a number in the column's unit. */
static int parse_time(const Cell *cell, enum TimeUnit unit, double *time_s) {
    if (looks_like_date(cell)) {
        return parse_utc(cell, time_s);
    }
    if (rins_parse_number(cell->start, cell->len, time_s) != RINS_ERROR_OK) {
        return 0;
    }
    if (unit == MILLISECONDS) {
        *time_s = *time_s / 1000.0;
    }
    return 1;
}

static void fail(const char *what, RinsError error) {
    fprintf(stderr, "error: %s: %s\n", what, rins_error_name(error));
    exit(1);
}

int main(void) {
    enum { MAX_CELLS = 256 };
    static Cell cells[MAX_CELLS];
    size_t column[COLUMNS]; /* the cell index of each column (the time's first) */
    enum TimeUnit time_unit = SECONDS;
    char separator = ',';
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
        if (!have_header) {
            separator = separator_of(line);
        }
        n = split(line, separator, cells, MAX_CELLS);
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
                size_t found = 0, unit;
                for (unit = 0; unit < (k == 0 ? 3u : 1u) && found == 0; unit++) {
                    const char *name = k == 0 ? TIME_NAMES[unit] : COLUMN_NAMES[k];
                    for (i = 0; i < n; i++) {
                        if (names(&cells[i], name)) {
                            column[k] = i;
                            found++;
                        }
                    }
                    if (k == 0 && found > 0) {
                        time_unit = (enum TimeUnit)unit;
                    }
                }
                if (found != 1) {
                    fprintf(stderr, "error: -:%lu: bad header: column \"%s\"%s %s\n", line_no, COLUMN_NAMES[k],
                            k == 0 ? " (or \"time_ms\", \"time_utc\")" : "", found ? "appears twice" : "is missing");
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
                } else if (k == 0 ? !parse_time(&cells[i], time_unit, &value[k])
                                  : rins_parse_number(cells[i].start, cells[i].len, &value[k]) != RINS_ERROR_OK) {
                    problem = k == 0 ? "not a time" : "not a number";
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
