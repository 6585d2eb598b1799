// QEMU TCG plugin: executed-instruction histogram by guest PC, for profiling the firmware.
// Build: gcc -O2 -shared -fPIC -fvisibility=hidden -DPLUGIN_API=1 -o libpcprofile.so pcprofile.c
// (PLUGIN_API=1 for QEMU 7.2, 2 for QEMU 10). Run: qemu-system-arm ... -plugin ./libpcprofile.so,out=FILE
// Counts PCs below 1 MiB (the firmware's code); rewrites FILE ("pc count" lines) every 2^26
// instructions, so the file is current even if QEMU is killed.
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
#define SLOTS (1u << 19)
static uint64_t counts[SLOTS], total;
static char out_path[512];
static void dump(void) {
  FILE *f = fopen(out_path, "w"); if (!f) return;
  for (uint32_t i = 0; i < SLOTS; i++) if (counts[i]) fprintf(f, "%x %llu\n", i * 2, (unsigned long long)counts[i]);
  fclose(f);
}
static void on_insn(unsigned int v, void *u) {
  counts[(uintptr_t)u]++;
  if ((++total & ((1ull << 26) - 1)) == 0) dump();
}
static void on_trans(qid id, struct qemu_plugin_tb *tb) {
  for (size_t i = 0; i < qemu_plugin_tb_n_insns(tb); i++) {
    struct qemu_plugin_insn *in = qemu_plugin_tb_get_insn(tb, i); uint64_t pc = qemu_plugin_insn_vaddr(in);
    if (pc / 2 < SLOTS) qemu_plugin_register_vcpu_insn_exec_cb(in, on_insn, 0, (void *)(uintptr_t)(pc / 2)); } }
__attribute__((visibility("default"))) int qemu_plugin_install(qid id, const qemu_info_t *info, int argc, char **argv) {
  strcpy(out_path, "pcprofile.txt");
  for (int i = 0; i < argc; i++) if (!strncmp(argv[i], "out=", 4)) snprintf(out_path, sizeof out_path, "%s", argv[i] + 4);
  qemu_plugin_register_vcpu_tb_trans_cb(id, on_trans); return 0; }
