//! The Cortex-M suite: runs every case of `bushing_tests::CASES` and ends
//! with `N passed, N failed`. On a Cortex-M target it runs under QEMU and the
//! verdict is QEMU's exit code (semihosting exit); on the host it is a plain
//! program with the same output.
#![cfg_attr(target_os = "none", no_std, no_main)]

#[cfg(target_os = "none")]
mod target {
    use cortex_m as _;
    use cortex_m_rt::entry;
    use cortex_m_semihosting::{debug, hprintln};
    use panic_semihosting as _;

    #[entry]
    fn main() -> ! {
        hprintln!("running {} cases on Cortex-M", bushing_tests::CASES.len());
        let failed = bushing_tests::run_all(|line| hprintln!("{}", line));
        debug::exit(if failed == 0 {
            debug::EXIT_SUCCESS
        } else {
            debug::EXIT_FAILURE
        });
        loop {
            cortex_m::asm::nop();
        }
    }
}

#[cfg(not(target_os = "none"))]
fn main() {
    println!("running {} cases on the host", bushing_tests::CASES.len());
    let failed = bushing_tests::run_all(|line| println!("{line}"));
    std::process::exit(if failed == 0 { 0 } else { 1 });
}
