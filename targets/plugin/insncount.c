/* Executed-instruction counter for QEMU TCG plugins (QEMU 7.2, plugin API 1), one vCPU.
 *
 *   -plugin libinsncount.so                      every guest instruction; prints "insns: N"
 *   -plugin libinsncount.so,lo=0xA,hi=0xB         only instructions with A <= PC < B
 *   -plugin libinsncount.so,start=0xS,stop=0xE    windows: from each execution of the
 *                                                 instruction at S to the next one at E
 *                                                 (callees included); prints "window K: N"
 *                                                 at the end of each window
 *
 * Counts are exact and repeatable: each translated block adds its instruction count when it
 * executes (window mode), or each instruction adds one inline (range mode). Output goes to
 * stderr. Built by build.sh against the qemu-plugin.h of the installed QEMU's Debian source. */
#include <inttypes.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <qemu-plugin.h>

QEMU_PLUGIN_EXPORT int qemu_plugin_version = QEMU_PLUGIN_VERSION;

#define UNSET 1 /* an odd address: never a Thumb instruction's PC once bit 0 is cleared */
#define START_BIT (1u << 30)
#define STOP_BIT (1u << 31)

static uint64_t count, lo = 0, hi = UINT64_MAX, start = UNSET, stop = UNSET;
static uint64_t window_start;
static int on, windows;

/* Window mode: one callback per executed block; userdata = instruction count | marker bits. */
static void block_exec(unsigned int vcpu, void *userdata)
{
    uintptr_t u = (uintptr_t)userdata;
    if ((u & START_BIT) && !on) {
        on = 1;
        window_start = count;
    }
    if ((u & STOP_BIT) && on) {
        on = 0;
        fprintf(stderr, "window %d: %" PRIu64 "\n", ++windows, count - window_start);
    }
    if (on)
        count += u & 0xffff;
}

static void block_trans(qemu_plugin_id_t id, struct qemu_plugin_tb *tb)
{
    size_t n = qemu_plugin_tb_n_insns(tb);
    if (start != UNSET) {
        /* A marker must begin a block: the markers are function entries (branch targets). */
        uint64_t pc = qemu_plugin_tb_vaddr(tb);
        uintptr_t u = n | (pc == start ? START_BIT : 0) | (pc == stop ? STOP_BIT : 0);
        qemu_plugin_register_vcpu_tb_exec_cb(tb, block_exec, QEMU_PLUGIN_CB_NO_REGS, (void *)u);
        return;
    }
    for (size_t i = 0; i < n; i++) {
        struct qemu_plugin_insn *insn = qemu_plugin_tb_get_insn(tb, i);
        uint64_t pc = qemu_plugin_insn_vaddr(insn);
        if (pc >= lo && pc < hi)
            qemu_plugin_register_vcpu_insn_exec_inline(insn, QEMU_PLUGIN_INLINE_ADD_U64, &count, 1);
    }
}

static void at_exit(qemu_plugin_id_t id, void *p)
{
    if (start == UNSET)
        fprintf(stderr, "insns: %" PRIu64 "\n", count);
}

QEMU_PLUGIN_EXPORT int qemu_plugin_install(qemu_plugin_id_t id, const qemu_info_t *info,
                                           int argc, char **argv)
{
    for (int i = 0; i < argc; i++) {
        char *v = strchr(argv[i], '=');
        uint64_t x = v ? strtoull(v + 1, NULL, 0) : 0;
        if (!strncmp(argv[i], "lo=", 3))
            lo = x;
        else if (!strncmp(argv[i], "hi=", 3))
            hi = x;
        else if (!strncmp(argv[i], "start=", 6))
            start = x & ~1ull; /* Thumb symbols have bit 0 set */
        else if (!strncmp(argv[i], "stop=", 5))
            stop = x & ~1ull;
        else {
            fprintf(stderr, "insncount: unknown argument %s\n", argv[i]);
            return -1;
        }
    }
    qemu_plugin_register_vcpu_tb_trans_cb(id, block_trans);
    qemu_plugin_register_atexit_cb(id, at_exit, NULL);
    return 0;
}
