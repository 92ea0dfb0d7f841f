"""scripts/check-isa-isolation on made-up disassemblies (`objdump -d -C -w` text): it passes kernels that keep their
ISA and fails, naming the function and the instruction, on each kind of escape. (isa.avx_only_in_kernels runs it on
the qdmr binary.)"""
import subprocess
import sys
from pathlib import Path

SCRIPT = Path(__file__).resolve().parents[2] / "scripts" / "check-isa-isolation"

HEAD = "\nqdmr:     file format elf64-x86-64\n\n\nDisassembly of section .text:\n"


def function(address, name, *instructions):
    """One function's text as objdump prints it: a blank line, the header, then "  address:\\tbytes \\ttext"."""
    lines = [f"\n{address:016x} <{name}>:"]
    for i, (raw, text) in enumerate(instructions):
        lines.append(f"  {address + 4 * i:x}:\t{raw} \t{text}")
    return "\n".join(lines) + "\n"


def check(tmp_path, *functions):
    path = tmp_path / "disassembly.txt"
    path.write_text(HEAD + "".join(functions))
    run = subprocess.run([sys.executable, str(SCRIPT), "--disassembly", str(path)], capture_output=True, text=True)
    return run.returncode, run.stdout + run.stderr


BASELINE = function(0x401000, "qdmr::draw(qdmr::Scene const&)", ("55", "push   %rbp"),
                    ("66 0f 28 c1", "movapd %xmm1,%xmm0"), ("e8 00 00 00 00", "call   401100 <qdmr::avx2::x()>"),
                    ("0f 01 c1", "vmcall"))  # a VMX instruction: its name starts with v, it is no AVX
AVX2_KERNEL = function(0x402000, "qdmr::avx2::NormalMappingProgram::shade(qdmr::Fragments const&) const",
                       ("c5 fc 28 c1", "vmovaps %ymm1,%ymm0"), ("c5 f4 58 c2", "vaddps %ymm2,%ymm1,%ymm1"))
AVX512_KERNEL = function(0x403000, "qdmr::avx512::TileRasterizer::prepare()",
                         ("62 f1 7c 48 28 c1", "vmovaps %zmm1,%zmm0"), ("c5 f8 77", "vzeroupper"),
                         ("62 f1 7c 48 c2 c9 01", "vcmpltps %zmm1,%zmm0,%k1"))
XSIMD_AVX = function(0x404000, "xsimd::batch<float, xsimd::avx2> xsimd::kernel::sqrt<xsimd::avx2>(...)",
                     ("c5 fc 51 c0", "vsqrtps %ymm0,%ymm0"))


def test_kernels_that_keep_their_isa_pass(tmp_path):
    code, out = check(tmp_path, BASELINE, AVX2_KERNEL, AVX512_KERNEL, XSIMD_AVX)
    assert code == 0, out
    assert "(4 functions, 3 in the AVX kernels)" in out


def test_an_avx_instruction_outside_the_kernels_fails(tmp_path):
    leaked = function(0x405000, "qdmr::shading::normalize(qdmr::Vec3 const&)", ("55", "push   %rbp"),
                      ("c5 f8 28 c1", "vmovaps %xmm1,%xmm0"), ("c5 f8 58 c1", "vaddps %xmm1,%xmm0,%xmm0"))
    code, out = check(tmp_path, BASELINE, leaked, AVX2_KERNEL)
    assert code == 1
    assert "1 function(s)" in out and "qdmr::shading::normalize" in out
    assert "AVX: vmovaps %xmm1,%xmm0" in out and "vaddps" not in out  # the first such instruction only


def test_a_ymm_register_outside_the_kernels_fails_whatever_its_mnemonic(tmp_path):
    leaked = function(0x405000, "std::vector<float>::resize(unsigned long)", ("90", "nop"),
                      ("66 0f 6f 00", "movdqa (%rax),%ymm3"))  # made up: a ymm operand alone decides
    code, out = check(tmp_path, leaked)
    assert code == 1 and "AVX: movdqa (%rax),%ymm3" in out


def test_avx512_in_the_avx2_kernel_fails_by_each_sign(tmp_path):
    cases = {
        "zmm": ("c5 fc 28 c1", "vmovaps %zmm1,%zmm0"),
        "mask register": ("c5 fc 28 c1", "kmovw %k1,%eax"),
        "upper register": ("c5 fc 28 c1", "vmovaps %ymm17,%ymm0"),
        "EVEX prefix": ("62 f1 7c 28 28 c1", "vmovaps %ymm1,%ymm0"),
        "EVEX after a segment prefix": ("64 62 f1 7c 28 28 00", "vmovaps %fs:(%rax),%ymm0"),
    }
    for sign, instruction in cases.items():
        kernel = function(0x406000, "qdmr::avx2::qdm_pair(...)", ("c5 fc 28 c1", "vmovaps %ymm1,%ymm0"), instruction)
        code, out = check(tmp_path, kernel, AVX512_KERNEL)
        assert code == 1, sign
        assert f"AVX-512: {instruction[1]}" in out, (sign, out)


def test_avx512_outside_every_kernel_is_reported_as_avx512_and_avx_apart(tmp_path):
    leaked = function(0x407000, "qdmr::Texture::decode()", ("c5 fc 28 c1", "vmovaps %ymm1,%ymm0"),
                      ("62 f1 7c 48 28 c1", "vmovaps %zmm1,%zmm0"))
    code, out = check(tmp_path, leaked)
    assert code == 1
    assert "AVX: vmovaps %ymm1,%ymm0" in out and "AVX-512: vmovaps %zmm1,%zmm0" in out


def test_a_byte_0x62_inside_an_instruction_is_not_evex(tmp_path):
    code, out = check(tmp_path, function(0x408000, "qdmr::avx2::x()", ("48 8b 44 62 08", "mov    0x8(%rdx,%riz,2),%rax")))
    assert code == 0, out


def test_the_last_function_of_the_text_is_checked(tmp_path):
    last = function(0x409000, "qdmr::tail()", ("c5 fc 28 c1", "vmovaps %ymm1,%ymm0")).rstrip("\n")
    code, out = check(tmp_path, BASELINE, last)
    assert code == 1 and "qdmr::tail()" in out
