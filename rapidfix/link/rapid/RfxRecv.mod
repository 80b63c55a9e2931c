MODULE RfxRecv
  ! rapidfix serial receiver, protocol version 1.
  !
  ! Load this module once in a spare task and run RfxRecvMain. It waits on a
  ! serial channel for programs sent by `rapidfix upload PROG --port PORT`,
  ! writes each under a temporary name, reads it back to verify size and
  ! CRC, and only then renames it into place and, if asked, loads it.
  !
  ! Frame, both directions (the layout is documented in rapidfix/link/frames.py):
  !   SOH(1)=1  kind(1)  seq(2, high byte first)  len(1)=0..80  payload(len)  crc(2)
  ! crc is CRC-16/CCITT-FALSE over kind, seq, len and payload.
  ! Kinds: host H=HELLO D=DATA E=END; controller R=READY K=ACK N=NAK B=BUSY F=DONE.
  !
  ! States: 0 IDLE, 1 RECEIVING, 2 FINISHED (the same as rapidfix/link/receiver.py).
  ! Data frames are taken in order only (go-back-N): frame expected is appended,
  ! an older frame is a duplicate and only acknowledged, a newer frame means a
  ! gap and gets one NAK. Resume after a broken link: a HELLO for the same file
  ! while RECEIVING is answered with READY(expected).
  ! Bytes are read one by one with ReadBin into num arrays and written with
  ! WriteBin, so any byte value (NUL included) passes; strings are not used
  ! for data.

  CONST num RFX_VERSION := 1;
  CONST string RFX_CHANNEL := "com1:";
  CONST string RFX_DIR := "HOME:/";
  CONST string RFX_TEMP := ".rfxpart";
  CONST num RFX_MAXPAY := 80;
  CONST num RFX_IDLE_TIME := 10;
  CONST num RFX_BYTE_TIME := 0.5;
  CONST num RFX_BUSY_EVERY := 4096;

  CONST num SOH := 1;
  CONST num K_HELLO := 72;
  CONST num K_DATA := 68;
  CONST num K_END := 69;
  CONST num K_READY := 82;
  CONST num K_ACK := 75;
  CONST num K_NAK := 78;
  CONST num K_BUSY := 66;
  CONST num K_DONE := 70;

  CONST num S_IDLE := 0;
  CONST num S_RECEIVING := 1;
  CONST num S_FINISHED := 2;

  CONST num READY_ACCEPTED := 0;
  CONST num READY_VERSION_REFUSED := 1;
  CONST num READY_CANNOT_CREATE := 2;

  CONST num DONE_OK := 0;
  CONST num DONE_CHECK_FAILED := 1;
  CONST num DONE_FILE_ERROR := 2;
  CONST num DONE_LOAD_FAILED := 3;
  CONST num DONE_NO_TRANSFER := 4;

  VAR iodev rxChannel;
  VAR iodev rxFile;
  VAR bool rxFileOpen := FALSE;

  VAR num rxState := 0;
  VAR num rxExpected := 0;
  VAR bool rxNakSent := FALSE;
  VAR num rxDoneStatus := 4;

  ! identity of the transfer, from HELLO
  VAR string rxName := "";
  VAR num rxSize := 0;
  VAR num rxCrcHi := 0;
  VAR num rxCrcLo := 0;
  VAR num rxFlags := 0;

  ! the frame just read
  VAR num frKind := 0;
  VAR num frSeq := 0;
  VAR num frLen := 0;
  VAR num frPay{80};

  ! reply payload and the bytes of a reply frame
  VAR num txPay{8};
  VAR num txBuf{16};

  ! CRC register as two bytes
  VAR byte crcHi := 255;
  VAR byte crcLo := 255;

  PROC RfxRecvMain()
    Open RFX_CHANNEL, rxChannel \Bin;
    ClearIOBuff rxChannel;
    WHILE TRUE DO
      IF ReadFrame() THEN
        TEST frKind
        CASE K_HELLO:
          OnHello;
        CASE K_DATA:
          OnData;
        CASE K_END:
          OnEnd;
        DEFAULT:
          ! a kind this receiver does not know: ignored
        ENDTEST
      ENDIF
    ENDWHILE
  ENDPROC

  PROC CrcStart()
    crcHi := 255;
    crcLo := 255;
  ENDPROC

  PROC CrcByte(num value)
    ! One byte into the CRC-16/CCITT-FALSE register (crc16_step in checksum.py).
    ! BitLSh on a byte drops the bits shifted out of the low 8.
    VAR byte x;
    VAR byte oldLo;

    x := BitXOr(crcHi, value);
    x := BitXOr(x, BitRSh(x, 4));
    oldLo := crcLo;
    crcHi := BitXOr(BitXOr(oldLo, BitRSh(x, 3)), BitLSh(x, 4));
    crcLo := BitXOr(BitLSh(x, 5), x);
  ENDPROC

  FUNC bool ReadFrame()
    ! Read one frame; FALSE on a time-out, a bad length or a bad CRC.
    ! The bytes of a bad frame are consumed; the next call hunts for SOH again.
    VAR num b;
    VAR num hi;
    VAR num lo;
    VAR num i;

    b := ReadBin(rxChannel \Time:=RFX_IDLE_TIME);
    IF b <> SOH THEN
      RETURN FALSE;
    ENDIF
    CrcStart;
    frKind := ReadBin(rxChannel \Time:=RFX_BYTE_TIME);
    CrcByte frKind;
    hi := ReadBin(rxChannel \Time:=RFX_BYTE_TIME);
    CrcByte hi;
    lo := ReadBin(rxChannel \Time:=RFX_BYTE_TIME);
    CrcByte lo;
    frSeq := hi * 256 + lo;
    frLen := ReadBin(rxChannel \Time:=RFX_BYTE_TIME);
    CrcByte frLen;
    IF frLen > RFX_MAXPAY THEN
      RETURN FALSE;
    ENDIF
    i := 0;
    WHILE i < frLen DO
      i := i + 1;
      frPay{i} := ReadBin(rxChannel \Time:=RFX_BYTE_TIME);
      CrcByte frPay{i};
    ENDWHILE
    hi := ReadBin(rxChannel \Time:=RFX_BYTE_TIME);
    lo := ReadBin(rxChannel \Time:=RFX_BYTE_TIME);
    RETURN hi = crcHi AND lo = crcLo;
  ERROR
    IF ERRNO = ERR_DEV_MAXTIME THEN
      RETURN FALSE;
    ENDIF
    RAISE;
  ENDFUNC

  PROC SendFrame(num kind, num seq, num plen)
    ! Send one frame; its payload is txPay{1..plen}.
    VAR num n;
    VAR num i;

    CrcStart;
    txBuf{1} := SOH;
    txBuf{2} := kind;
    txBuf{3} := seq DIV 256;
    txBuf{4} := seq MOD 256;
    txBuf{5} := plen;
    n := 5;
    i := 0;
    WHILE i < plen DO
      i := i + 1;
      n := n + 1;
      txBuf{n} := txPay{i};
    ENDWHILE
    i := 1;
    WHILE i < n DO
      i := i + 1;
      CrcByte txBuf{i};
    ENDWHILE
    txBuf{n + 1} := crcHi;
    txBuf{n + 2} := crcLo;
    WriteBin rxChannel, txBuf, n + 2;
  ENDPROC

  PROC SendReady(num status)
    txPay{1} := RFX_VERSION;
    txPay{2} := status;
    SendFrame K_READY, rxExpected, 2;
  ENDPROC

  PROC SendDone()
    txPay{1} := rxDoneStatus;
    SendFrame K_DONE, rxExpected, 1;
  ENDPROC

  PROC OnHello()
    ! HELLO payload: version, flags, size(4), crc(2), name
    VAR num flags;
    VAR num size;
    VAR string name;
    VAR num i;

    IF frLen < 9 THEN
      RETURN;
    ENDIF
    IF frPay{1} <> RFX_VERSION THEN
      txPay{1} := RFX_VERSION;
      txPay{2} := READY_VERSION_REFUSED;
      SendFrame K_READY, 0, 2;
      RETURN;
    ENDIF
    flags := frPay{2};
    size := ((frPay{3} * 256 + frPay{4}) * 256 + frPay{5}) * 256 + frPay{6};
    name := "";
    i := 8;
    WHILE i < frLen DO
      i := i + 1;
      name := name + ByteToStr(frPay{i} \Char);
    ENDWHILE
    rxNakSent := FALSE;
    IF rxState = S_RECEIVING AND name = rxName AND size = rxSize AND frPay{7} = rxCrcHi AND frPay{8} = rxCrcLo AND flags = rxFlags THEN
      ! the same file again: resume where the link broke
      SendReady READY_ACCEPTED;
      RETURN;
    ENDIF
    DropTemp;
    rxState := S_IDLE;
    rxExpected := 0;
    IF StrFind(name, 1, "/\\:") <= StrLen(name) THEN
      SendReady READY_CANNOT_CREATE;
      RETURN;
    ENDIF
    rxName := name;
    rxSize := size;
    rxCrcHi := frPay{7};
    rxCrcLo := frPay{8};
    rxFlags := flags;
    Open RFX_DIR \File:=rxName + RFX_TEMP, rxFile \Write \Bin;
    rxFileOpen := TRUE;
    rxState := S_RECEIVING;
    SendReady READY_ACCEPTED;
  ERROR
    IF ERRNO = ERR_FILEOPEN THEN
      rxFileOpen := FALSE;
      rxState := S_IDLE;
      SendReady READY_CANNOT_CREATE;
      RETURN;
    ENDIF
    RAISE;
  ENDPROC

  PROC OnData()
    IF rxState <> S_RECEIVING THEN
      RETURN;
    ENDIF
    IF frSeq = rxExpected THEN
      WriteBin rxFile, frPay, frLen;
      rxExpected := rxExpected + 1;
      rxNakSent := FALSE;
      SendFrame K_ACK, rxExpected, 0;
    ELSEIF frSeq < rxExpected THEN
      ! a duplicate: written already, acknowledge again
      SendFrame K_ACK, rxExpected, 0;
    ELSEIF NOT rxNakSent THEN
      ! a gap: ask once for the missing frame
      rxNakSent := TRUE;
      SendFrame K_NAK, rxExpected, 0;
    ENDIF
  ENDPROC

  PROC OnEnd()
    ! END payload: size(4), crc(2); seq is the number of data frames
    VAR num size;
    VAR string path;

    IF rxState = S_FINISHED AND frSeq = rxExpected THEN
      SendDone;
      RETURN;
    ENDIF
    IF rxState <> S_RECEIVING THEN
      rxDoneStatus := DONE_NO_TRANSFER;
      SendDone;
      RETURN;
    ENDIF
    IF frSeq <> rxExpected THEN
      SendFrame K_NAK, rxExpected, 0;
      RETURN;
    ENDIF
    Close rxFile;
    rxFileOpen := FALSE;
    path := RFX_DIR + rxName;
    size := -1;
    IF frLen = 6 THEN
      size := ((frPay{1} * 256 + frPay{2}) * 256 + frPay{3}) * 256 + frPay{4};
    ENDIF
    IF size = rxSize AND frPay{5} = rxCrcHi AND frPay{6} = rxCrcLo AND VerifyTemp() THEN
      rxDoneStatus := DONE_OK;
      PutInPlace path;
    ELSE
      RemoveFile path + RFX_TEMP;
      rxDoneStatus := DONE_CHECK_FAILED;
    ENDIF
    rxState := S_FINISHED;
    SendDone;
  ENDPROC

  FUNC bool VerifyTemp()
    ! Read the temporary file back: its size and CRC must be those of HELLO.
    VAR num b;
    VAR num count;

    Open RFX_DIR \File:=rxName + RFX_TEMP, rxFile \Read \Bin;
    rxFileOpen := TRUE;
    CrcStart;
    count := 0;
    b := ReadBin(rxFile);
    WHILE b <> EOF_BIN DO
      CrcByte b;
      count := count + 1;
      IF count MOD RFX_BUSY_EVERY = 0 THEN
        SendFrame K_BUSY, 0, 0;
      ENDIF
      b := ReadBin(rxFile);
    ENDWHILE
    Close rxFile;
    rxFileOpen := FALSE;
    RETURN count = rxSize AND crcHi = rxCrcHi AND crcLo = rxCrcLo;
  ENDFUNC

  PROC PutInPlace(string path)
    ! Replace the real file by the verified one, then load it if HELLO asked.
    IF IsFile(path) THEN
      RemoveFile path;
    ENDIF
    RenameFile path + RFX_TEMP, path;
    IF BitAnd(rxFlags, 1) = 1 THEN
      rxDoneStatus := DONE_LOAD_FAILED;
      Load \Dynamic, path;
      rxDoneStatus := DONE_OK;
    ENDIF
  ERROR
    IF rxDoneStatus = DONE_OK THEN
      rxDoneStatus := DONE_FILE_ERROR;
    ENDIF
    RETURN;
  ENDPROC

  PROC DropTemp()
    ! Close and remove the temporary file of an unfinished transfer.
    IF rxFileOpen THEN
      Close rxFile;
      rxFileOpen := FALSE;
      RemoveFile RFX_DIR + rxName + RFX_TEMP;
    ENDIF
  ERROR
    RETURN;
  ENDPROC
ENDMODULE
