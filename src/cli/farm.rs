//! Rendering on a cluster through its own scheduler: the shell script that submits a
//! render's shards as a Slurm job array and the merge as a job that waits for them.
//!
//! ```text
//! pbrt-sppm plan --slurm --passes 256 --shards 16 scene.pbrt > submit.sh
//! sh submit.sh
//! ```
//! Shard i of K renders passes i·N/K to (i+1)·N/K − 1 of N ([`shard_range`], the same
//! arithmetic as `tools/slurm/shard.sbatch` and `tools/k8s/shards.yaml`). The script
//! carries the two batch scripts of `tools/slurm/` inside it, so it needs nothing but
//! the pbrt-sppm binary on the nodes and a folder they can all write.

use std::ops::Range;

/// The array task's batch script.
pub const SHARD_SBATCH: &str = include_str!("../../tools/slurm/shard.sbatch");
/// The merge job's batch script.
pub const MERGE_SBATCH: &str = include_str!("../../tools/slurm/merge.sbatch");

/// A render split into shards.
#[derive(Clone, Debug)]
pub struct ShardPlan {
    /// The pbrt-sppm binary, as the nodes will find it.
    pub binary: String,
    pub scene: String,
    /// The passes of the whole render (its `--spp`).
    pub passes: u32,
    pub shards: u32,
    /// The folder the parts are written to.
    pub parts: String,
    pub outfile: String,
    pub cpus_per_task: u32,
    /// More `render` options for every shard.
    pub render_args: Vec<String>,
}

/// The passes shard `i` of `shards` renders.
pub fn shard_range(i: u32, passes: u32, shards: u32) -> Range<u32> {
    let at = |i: u32| (i as u64 * passes as u64 / shards as u64) as u32;
    at(i)..at(i + 1)
}

/// A word the shell reads back unchanged.
pub fn quote(s: &str) -> String {
    if !s.is_empty() && s.bytes().all(|b| b.is_ascii_alphanumeric() || b"/._-=+:,@".contains(&b)) {
        return s.to_string();
    }
    format!("'{}'", s.replace('\'', r"'\''"))
}

/// Why a plan cannot be made.
#[derive(Debug, PartialEq, thiserror::Error)]
pub enum PlanError {
    #[error("--passes and --shards must be at least 1")]
    Empty,
    #[error("{shards} shards of {passes} passes would leave shards empty")]
    EmptyShards { shards: u32, passes: u32 },
}

impl ShardPlan {
    /// Checks the counts: at least one pass per shard.
    pub fn new(base: ShardPlan) -> Result<ShardPlan, PlanError> {
        if base.passes == 0 || base.shards == 0 {
            return Err(PlanError::Empty);
        }
        if base.shards > base.passes {
            return Err(PlanError::EmptyShards { shards: base.shards, passes: base.passes });
        }
        Ok(base)
    }

    /// A POSIX shell script that writes the two batch scripts into the parts folder and
    /// submits the shard array and the merge job (`afterok` on the array).
    pub fn slurm_script(&self) -> String {
        let (n, k) = (self.passes, self.shards);
        let ranges: Vec<String> =
            (0..k).map(|i| shard_range(i, n, k)).map(|r| format!("{}..{}", r.start, r.end)).collect();
        let extra: Vec<String> = self.render_args.iter().map(|a| quote(a)).collect();
        let parts = quote(&self.parts);
        let mut s = format!(
            "#!/bin/sh\n# pbrt-sppm plan: {n} independent passes of {} in {k} shards, then a merge.\n\
             # shard passes: {}\nset -eu\n",
            self.scene,
            ranges.join(" ")
        );
        s += &format!(
            "bin={}\nscene={}\nparts={parts}\nout={}\n",
            quote(&self.binary),
            quote(&self.scene),
            quote(&self.outfile)
        );
        s += "mkdir -p \"$parts\"\n";
        s += "if ls \"$parts\"/part-*.exr >/dev/null 2>&1; then\n    echo \"$parts already holds parts; \
              move them away or re-run single shards with sbatch (see $parts/shard.sbatch)\" >&2\n    exit 1\nfi\n";
        for (name, text) in [("shard.sbatch", SHARD_SBATCH), ("merge.sbatch", MERGE_SBATCH)] {
            s += &format!("cat > \"$parts/{name}\" <<'PBRT_SPPM_EOF'\n{text}PBRT_SPPM_EOF\n");
        }
        s += &format!(
            "array=$(sbatch --parsable --array=0-{} --cpus-per-task={} --output=\"$parts/shard-%a.log\" \
             \"$parts/shard.sbatch\" \"$bin\" \"$scene\" {n} {k} \"$parts\"{})\n",
            k - 1,
            self.cpus_per_task,
            extra.iter().map(|a| format!(" {a}")).collect::<String>()
        );
        s += "array=${array%%;*}\n";
        s += "merge=$(sbatch --parsable --dependency=afterok:\"$array\" --output=\"$parts/merge.log\" \
              \"$parts/merge.sbatch\" \"$bin\" \"$parts\" \"$out\")\n";
        s += "merge=${merge%%;*}\n";
        s += "echo \"submitted shards as job $array and the merge as job $merge; the image will be $out\"\n";
        s
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn shards_cover_the_passes_once_and_evenly() {
        for (n, k) in [(64, 4), (10, 3), (7, 7), (1, 1), (u32::MAX, 5)] {
            let mut next = 0;
            for i in 0..k {
                let r = shard_range(i, n, k);
                assert_eq!(r.start, next);
                assert!(r.end > r.start && (r.end - r.start) as u64 <= (n as u64).div_ceil(k as u64));
                next = r.end;
            }
            assert_eq!(next, n);
        }
    }

    #[test]
    fn quoting_survives_the_shell() {
        assert_eq!(quote("/a/b.pbrt"), "/a/b.pbrt");
        assert_eq!(quote("it's here"), r"'it'\''s here'");
        assert_eq!(quote(""), "''");
        assert_eq!(quote("$HOME"), "'$HOME'");
    }
}
