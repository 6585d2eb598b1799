// QEMU TCG plugin: exact count of guest instructions executed from PC `start` to PC `end`, over
// every such interval of the run, with a summary file.
// Build: gcc -O2 -shared -fPIC -fvisibility=hidden -DPLUGIN_API=1 -o libstepcount.so stepcount.c
// (PLUGIN_API=1 for QEMU 7.2, 2 for QEMU 10). Run: qemu-system-arm ...
//   -plugin ./libstepcount.so,start=0xADDR,end=0xADDR,out=FILE
// FILE is rewritten at every `end` with one line: "intervals N sum S max M min m".
#include <stdint.h>
#include <stdbool.h>
#include <stddef.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
typedef uint64_t qid; struct qemu_plugin_tb; struct qemu_plugin_insn;
typedef struct { const char *target_name; struct { int min, cur; } version; bool system_emulation;
                 union { struct { int smp_vcpus, max_vcpus; } system; }; } qemu_info_t;
typedef void (*vcpu_cb)(unsigned int, void *);
void qemu_plugin_register_vcpu_tb_trans_cb(qid, void (*)(qid, struct qemu_plugin_tb *));
void qemu_plugin_register_vcpu_insn_exec_cb(struct qemu_plugin_insn *, vcpu_cb, int, void *);
size_t qemu_plugin_tb_n_insns(const struct qemu_plugin_tb *);
struct qemu_plugin_insn *qemu_plugin_tb_get_insn(const struct qemu_plugin_tb *, size_t);
uint64_t qemu_plugin_insn_vaddr(const struct qemu_plugin_insn *);
__attribute__((visibility("default"))) int qemu_plugin_version = PLUGIN_API;
static uint64_t total, c0, start_pc, end_pc, n, sum, max, min = UINT64_MAX;
static bool open_interval;
static char out_path[512] = "stepcount.txt";
static void on_insn(unsigned int v, void *u) { total++; }
static void on_start(unsigned int v, void *u) { c0 = total; open_interval = true; }
static void on_end(unsigned int v, void *u) {
  if (!open_interval) return;
  open_interval = false;
  uint64_t d = total - c0; n++; sum += d; if (d > max) max = d; if (d < min) min = d;
  FILE *f = fopen(out_path, "w");
  if (f) { fprintf(f, "intervals %llu sum %llu max %llu min %llu\n", (unsigned long long)n, (unsigned long long)sum,
                   (unsigned long long)max, (unsigned long long)min); fclose(f); } }
static void on_trans(qid id, struct qemu_plugin_tb *tb) {
  for (size_t i = 0; i < qemu_plugin_tb_n_insns(tb); i++) {
    struct qemu_plugin_insn *in = qemu_plugin_tb_get_insn(tb, i); uint64_t pc = qemu_plugin_insn_vaddr(in);
    if (pc == start_pc) qemu_plugin_register_vcpu_insn_exec_cb(in, on_start, 0, NULL);
    if (pc == end_pc) qemu_plugin_register_vcpu_insn_exec_cb(in, on_end, 0, NULL);
    qemu_plugin_register_vcpu_insn_exec_cb(in, on_insn, 0, NULL); } }
__attribute__((visibility("default"))) int qemu_plugin_install(qid id, const qemu_info_t *info, int argc, char **argv) {
  for (int i = 0; i < argc; i++) {
    if (!strncmp(argv[i], "start=", 6)) start_pc = strtoull(argv[i] + 6, NULL, 0) & ~1ull;
    if (!strncmp(argv[i], "end=", 4)) end_pc = strtoull(argv[i] + 4, NULL, 0) & ~1ull;
    if (!strncmp(argv[i], "out=", 4)) snprintf(out_path, sizeof out_path, "%s", argv[i] + 4); }
  qemu_plugin_register_vcpu_tb_trans_cb(id, on_trans); return 0; }
