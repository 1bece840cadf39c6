//! The C boundary: QEMU's plugin interface (version 1, QEMU 7.2 and later),
//! declared here for the few calls the recorder needs. Every `unsafe` of
//! the crate is in this file.
#![allow(unsafe_code)]

use std::ffi::{CStr, c_char, c_int, c_void};
use std::fs::File;
use std::io::BufWriter;
use std::sync::Mutex;

use crate::{Marks, Recorder};

/// Opaque QEMU types, only ever behind pointers QEMU gives.
#[repr(C)]
pub struct QemuPluginTb {
    _opaque: [u8; 0],
}

/// See [`QemuPluginTb`].
#[repr(C)]
pub struct QemuPluginInsn {
    _opaque: [u8; 0],
}

type TbTrans = extern "C" fn(id: u64, tb: *mut QemuPluginTb);
type VcpuUdata = extern "C" fn(vcpu: u32, udata: *mut c_void);
type Udata = extern "C" fn(id: u64, udata: *mut c_void);

/// `QEMU_PLUGIN_CB_NO_REGS`: the callback reads no guest register.
const NO_REGS: c_int = 0;

unsafe extern "C" {
    fn qemu_plugin_register_vcpu_tb_trans_cb(id: u64, cb: TbTrans);
    fn qemu_plugin_register_vcpu_tb_exec_cb(
        tb: *mut QemuPluginTb,
        cb: VcpuUdata,
        flags: c_int,
        udata: *mut c_void,
    );
    fn qemu_plugin_register_atexit_cb(id: u64, cb: Udata, udata: *mut c_void);
    fn qemu_plugin_tb_n_insns(tb: *const QemuPluginTb) -> usize;
    fn qemu_plugin_tb_vaddr(tb: *const QemuPluginTb) -> u64;
    fn qemu_plugin_tb_get_insn(tb: *const QemuPluginTb, idx: usize) -> *mut QemuPluginInsn;
    fn qemu_plugin_insn_vaddr(insn: *const QemuPluginInsn) -> u64;
    fn qemu_plugin_insn_size(insn: *const QemuPluginInsn) -> usize;
}

/// The plugin interface version this plugin was written for.
#[unsafe(no_mangle)]
pub static qemu_plugin_version: c_int = 1;

static RECORDER: Mutex<Option<Recorder<BufWriter<File>>>> = Mutex::new(None);

fn with_recorder(f: impl FnOnce(&mut Recorder<BufWriter<File>>)) {
    let mut guard = RECORDER.lock().unwrap_or_else(|e| e.into_inner());
    if let Some(r) = guard.as_mut() {
        f(r);
    }
}

/// `elf=PATH` and `out=PATH` from the plugin's arguments.
fn arguments(args: &[String]) -> Result<(String, String), String> {
    let mut elf = None;
    let mut out = None;
    for a in args {
        match a.split_once('=') {
            Some(("elf", v)) => elf = Some(v.to_string()),
            Some(("out", v)) => out = Some(v.to_string()),
            _ => return Err(format!("unknown argument '{a}' (want elf=PATH,out=PATH)")),
        }
    }
    match (elf, out) {
        (Some(e), Some(o)) => Ok((e, o)),
        _ => Err("need elf=PATH and out=PATH".into()),
    }
}

fn start(args: &[String]) -> Result<Recorder<BufWriter<File>>, String> {
    let (elf, out) = arguments(args)?;
    let bytes = std::fs::read(&elf).map_err(|e| format!("{elf}: {e}"))?;
    let marks = Marks::from_elf(&bytes).map_err(|e| format!("{elf}: {e}"))?;
    let file = File::create(&out).map_err(|e| format!("{out}: {e}"))?;
    Recorder::new(marks, BufWriter::new(file)).map_err(|e| format!("{out}: {e}"))
}

/// Called by QEMU once, when it loads the plugin.
#[unsafe(no_mangle)]
pub extern "C" fn qemu_plugin_install(
    id: u64,
    _info: *const c_void,
    argc: c_int,
    argv: *const *const c_char,
) -> c_int {
    let count = usize::try_from(argc).unwrap_or(0);
    let args: Vec<String> = (0..count)
        .map(|i| {
            // SAFETY: QEMU passes `argc` valid, NUL-terminated strings in
            // `argv`, alive for the duration of this call.
            unsafe { CStr::from_ptr(*argv.add(i)) }
                .to_string_lossy()
                .into_owned()
        })
        .collect();
    match start(&args) {
        Ok(r) => {
            *RECORDER.lock().unwrap_or_else(|e| e.into_inner()) = Some(r);
            // SAFETY: `id` is the one QEMU gave this call, and the
            // callbacks are `extern "C"` functions of the declared types.
            unsafe {
                qemu_plugin_register_vcpu_tb_trans_cb(id, translated);
                qemu_plugin_register_atexit_cb(id, finished, std::ptr::null_mut());
            }
            0
        }
        Err(why) => {
            eprintln!("qemu-mix: {why}");
            -1
        }
    }
}

extern "C" fn translated(_id: u64, tb: *mut QemuPluginTb) {
    // SAFETY: `tb` is the block QEMU is translating, valid for this call;
    // `n` instructions exist, so indices below `n` are valid.
    let (start, end, n) = unsafe {
        let n = qemu_plugin_tb_n_insns(tb);
        let start = qemu_plugin_tb_vaddr(tb);
        let end = match n.checked_sub(1) {
            Some(last) => {
                let insn = qemu_plugin_tb_get_insn(tb, last);
                qemu_plugin_insn_vaddr(insn) + qemu_plugin_insn_size(insn) as u64
            }
            None => start,
        };
        (start, end, n)
    };
    let mut id = None;
    with_recorder(|r| id = Some(r.translated(start, end, n as u64)));
    if let Some(id) = id {
        // SAFETY: as above; the user data is the block's id, an integer
        // carried in the pointer and never dereferenced.
        unsafe { qemu_plugin_register_vcpu_tb_exec_cb(tb, executed, NO_REGS, id as *mut c_void) };
    }
}

extern "C" fn executed(_vcpu: u32, udata: *mut c_void) {
    let id = udata as usize;
    with_recorder(|r| r.executed(id));
}

extern "C" fn finished(_id: u64, _udata: *mut c_void) {
    with_recorder(|r| {
        if let Err(why) = r.finish() {
            eprintln!("qemu-mix: {why}");
        }
    });
}
