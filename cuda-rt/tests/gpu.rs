//! The device API and the closest-hit pipeline on a real GPU, with the stand-in kernels of
//! `fixtures/probe.ll`. On a machine without CUDA every test prints one `skip: <reason>` line
//! and passes. The launch-failure test is in `gpu_fault.rs`: a fault spoils the context for
//! the whole process.

mod common;

use common::{device_or_skip, stack_limit_lock, PROBE_PTX};
use scion_cuda::error::STATUS_STACK_OVERFLOW;
use scion_cuda::trace::{GpuPipeline, RootRef};
use scion_cuda::{CudaError, DevicePtr, Grid, KernelArg, Module};
use scion_runtime::bvh::schema::binary_bvh;
use scion_runtime::bvh::{build_sah_binned, LogicalTree, SahOptions};
use scion_runtime::geom::{Hit, Ray, Triangle, Vec3};

fn triangles(n: u32) -> Vec<Triangle> {
    (0..n)
        .map(|i| {
            let x = (i % 17) as f32 * 2.0;
            let y = (i / 17) as f32 * 2.0;
            Triangle::new(
                Vec3::new(x, y, 0.0),
                Vec3::new(x + 1.0, y, 0.0),
                Vec3::new(x, y + 1.0, 0.5),
                1000 + i,
            )
        })
        .collect()
}

fn rays(n: usize) -> Vec<Ray> {
    (0..n)
        .map(|i| {
            let mut r = Ray::new(Vec3::new(i as f32, 0.0, -1.0), Vec3::new(0.0, 0.0, 1.0));
            r.tmax = 1.0 + i as f32;
            r
        })
        .collect()
}

#[test]
fn device_opens_and_describes_itself() {
    let Some(dev) = device_or_skip("device_opens_and_describes_itself") else {
        return;
    };
    let (free, total) = dev.memory().unwrap();
    println!(
        "device {}: {} (sm_{}{}), driver CUDA {}, {} of {} MiB free",
        dev.ordinal(),
        dev.name,
        dev.compute_capability.0,
        dev.compute_capability.1,
        scion_cuda::error::version_text(dev.driver.version),
        free >> 20,
        total >> 20
    );
    assert!(!dev.name.is_empty());
    assert!(total > 0 && free <= total);
    assert!(dev.compute_capability.0 >= 3);
}

#[test]
fn buffers_round_trip_and_start_zeroed() {
    let Some(dev) = device_or_skip("buffers_round_trip_and_start_zeroed") else {
        return;
    };
    let data: Vec<u32> = (0..10_000u32)
        .map(|i| i.wrapping_mul(2_654_435_761))
        .collect();
    let buf = dev.upload("words", &data).unwrap();
    assert_eq!(buf.len(), 40_000);
    assert_eq!(buf.ptr().0 % 256, 0, "cuMemAlloc aligns to 256 bytes");
    assert_eq!(buf.download::<u32>(data.len()).unwrap(), data);
    let zeroed = dev.alloc("zeroed", 1000).unwrap();
    assert!(zeroed.download::<u8>(1000).unwrap().iter().all(|&b| b == 0));
    let tris = triangles(50);
    let tbuf = dev.upload("triangles", &tris).unwrap();
    assert_eq!(tbuf.download::<Triangle>(50).unwrap(), tris);
    let empty = dev.alloc("empty", 0).unwrap();
    assert!(empty.is_empty());
    let e = zeroed.write(&[0u64; 200]).unwrap_err();
    assert_eq!(
        e.to_string(),
        "writing 1600 bytes into `zeroed`, which holds 1000 bytes"
    );
}

#[test]
fn out_of_memory_names_the_buffer() {
    let Some(dev) = device_or_skip("out_of_memory_names_the_buffer") else {
        return;
    };
    let (_, total) = dev.memory().unwrap();
    let e = dev.alloc("far too big", total * 4).unwrap_err();
    match &e {
        CudaError::OutOfMemory { buffer, bytes, .. } => {
            assert_eq!(buffer, "far too big");
            assert_eq!(*bytes, total * 4);
        }
        other => panic!("expected out of memory, got {other:?}"),
    }
    assert!(e
        .to_string()
        .starts_with("out of device memory allocating `far too big`"));
    // Not sticky: the context still works.
    assert!(dev.alloc("small", 64).is_ok());
}

#[test]
fn stack_limit_can_be_set_and_read() {
    let Some(dev) = device_or_skip("stack_limit_can_be_set_and_read") else {
        return;
    };
    let _lock = stack_limit_lock();
    let before = dev.stack_limit().unwrap();
    dev.set_stack_limit(8192).unwrap();
    assert!(dev.stack_limit().unwrap() >= 8192);
    dev.set_stack_limit(before).unwrap();
}

#[test]
fn bad_ptx_is_rejected_with_the_jit_log() {
    let Some(dev) = device_or_skip("bad_ptx_is_rejected_with_the_jit_log") else {
        return;
    };
    let bad = ".version 6.3\n.target sm_75\n.address_size 64\n\
               .visible .entry broken(\n.param .u64 p\n)\n{\n\tnot_an_instruction %r1;\n}\n";
    let e = match Module::load(&dev, bad) {
        Ok(_) => panic!("the driver accepted broken PTX"),
        Err(e) => e,
    };
    println!("{e}");
    match &e {
        CudaError::ModuleLoad { log, .. } => assert!(!log.trim().is_empty(), "empty JIT log"),
        other => panic!("expected a module load error, got {other:?}"),
    }
}

#[test]
fn ptx_for_a_newer_gpu_is_refused_before_the_jit() {
    let Some(dev) = device_or_skip("ptx_for_a_newer_gpu_is_refused_before_the_jit") else {
        return;
    };
    let newer = format!("sm_{}0", dev.compute_capability.0 + 1);
    let ptx = PROBE_PTX.replacen(".target sm_75", &format!(".target {newer}"), 1);
    let e = Module::load(&dev, &ptx)
        .err()
        .expect("PTX for a newer GPU loaded");
    let m = e.to_string();
    println!("{m}");
    assert!(
        m.contains(&format!("the PTX is for {newer} but the device is sm_")),
        "{m}"
    );
    assert!(m.contains("compile for it with --cpu sm_"), "{m}");
}

#[test]
fn kernels_are_looked_up_and_arguments_checked() {
    let Some(dev) = device_or_skip("kernels_are_looked_up_and_arguments_checked") else {
        return;
    };
    let m = Module::load(&dev, PROBE_PTX).unwrap();
    let e = m.kernel("no_such_kernel").err().unwrap();
    assert!(matches!(e, CudaError::MissingKernel { .. }));
    assert!(e.to_string().contains("scion_probe_Fixture_kernel"), "{e}");
    let k = m.kernel("scion_Fixture_sizes_kernel").unwrap();
    let e = k.run(Grid::SINGLE, &[KernelArg::U32(1)]).unwrap_err();
    assert!(matches!(e, CudaError::BadArguments { .. }), "{e:?}");
    // A correct launch of the sizes kernel on a hand-made tree view.
    let view = [0u64, 0, 7u64, 0]; // prim_count (offset 24) = 7
    let view = dev.upload("view", &view).unwrap();
    let sizes = dev.alloc("sizes", 16).unwrap();
    k.run(
        Grid::SINGLE,
        &[KernelArg::Ptr(view.ptr()), KernelArg::Ptr(sizes.ptr())],
    )
    .unwrap();
    assert_eq!(sizes.download::<u64>(2).unwrap(), vec![7 * 40, 4]);
}

fn expected(tree: &LogicalTree, rays: &[Ray]) -> Vec<Hit> {
    let count = tree.primitives.len();
    let root = count as u32 - 1;
    rays.iter()
        .enumerate()
        .map(|(i, r)| Hit::from_best(r.tmax * 0.5, tree.primitives[i % count].id + root))
        .collect()
}

#[test]
fn pipeline_packs_on_the_device_and_traces() {
    let Some(dev) = device_or_skip("pipeline_packs_on_the_device_and_traces") else {
        return;
    };
    let names = vec!["triangles".to_string(), "count".to_string()];
    let p = GpuPipeline::new(&dev, PROBE_PTX, "Fixture", "probe", names, binary_bvh()).unwrap();
    assert_eq!(p.root_ref(), RootRef::U32);
    let tree = build_sah_binned(&triangles(300), &SahOptions::default());
    let lock = stack_limit_lock();
    let before = dev.stack_limit().unwrap();
    let packed = p.pack(&tree, tree.stats().depth).unwrap();
    assert_eq!(
        dev.stack_limit().unwrap(),
        before,
        "the stack limit is restored"
    );
    assert!(packed.pack_stack >= before);
    drop(lock);
    assert_eq!(packed.sizes, vec![300 * 40, 4]);
    let copied: Vec<Triangle> = packed.buffers[0].download(300).unwrap();
    assert_eq!(copied, tree.primitives);
    // Sizes around the block size: partial last blocks, one block, several.
    for n in [0, 1, 255, 256, 257, 1000, 100_000] {
        let rays = rays(n);
        let on_device = p.upload_rays(&rays).unwrap();
        let t = p.trace(&packed, &on_device).unwrap();
        assert_eq!(t.hits, expected(&tree, &rays), "n = {n}");
        // Tracing again re-initializes the results.
        let again = p.trace(&packed, &on_device).unwrap();
        assert_eq!(again.hits, t.hits, "n = {n}, second trace");
    }
    // A nonzero status from one ray fails the batch.
    let mut bad = rays(600);
    bad[517].tmin = -1.0;
    let on_device = p.upload_rays(&bad).unwrap();
    let e = p.trace(&packed, &on_device).unwrap_err();
    assert_eq!(
        e,
        CudaError::Status {
            kernel: "scion_probe_Fixture_kernel".into(),
            status: STATUS_STACK_OVERFLOW
        }
    );
    assert!(e.to_string().contains("traversal stack overflow"), "{e}");
    // The empty tree packs nothing; every ray misses.
    let empty = build_sah_binned::<scion_runtime::geom::Triangle>(&[], &SahOptions::default());
    let packed = p.pack(&empty, 0).unwrap();
    let t = p
        .trace(&packed, &p.upload_rays(&rays(10)).unwrap())
        .unwrap();
    assert_eq!(t.hits, vec![Hit::MISS; 10]);
}

#[test]
fn pipeline_rejects_a_module_without_the_kernels() {
    let Some(dev) = device_or_skip("pipeline_rejects_a_module_without_the_kernels") else {
        return;
    };
    let e = GpuPipeline::new(
        &dev,
        PROBE_PTX,
        "LinearBVH",
        "closest_hit",
        vec![],
        binary_bvh(),
    )
    .err()
    .unwrap();
    assert!(
        e.to_string()
            .starts_with("the PTX module has no kernel `scion_LinearBVH_sizes_kernel`"),
        "{e}"
    );
    let _ = DevicePtr(0);
}
